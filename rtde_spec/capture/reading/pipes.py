"""A capture read from a pipe (`tcpdump -w - | rtde-spec capture -`, `zcat x.pcap | ...`).

A pipe holds 64 kB unless asked for more, so a fast writer's capture came a 64 kB read at
a time: ~90 data packages a block, and every block costs the same numpy and Arrow set-up
as an 8 MB one. Read that way, a piped capture took 5-7x the CPU of the same file (100,000
packages: 3.9 s against 0.58 s). The pipe is widened as far as the system lets a user
(`/proc/sys/fs/pipe-max-size`, 1 MB by default), and the reader takes what waits in it
block by block; a live capture still reads as it comes (nothing waits for a block to fill).
"""

from __future__ import annotations

import os
import stat
from typing import IO

PIPE_MAX = "/proc/sys/fs/pipe-max-size"


def widen(f: IO[bytes], want: int) -> int:
    """Ask for a pipe of up to `want` bytes (the system's limit at most, never smaller than it
    is); returns its size after (0: not a pipe, or the system has no such call)."""
    try:
        import fcntl

        fd = f.fileno()
        if not stat.S_ISFIFO(os.fstat(fd).st_mode) or not hasattr(fcntl, "F_SETPIPE_SZ"):
            return 0
        size = fcntl.fcntl(fd, fcntl.F_GETPIPE_SZ)
        want = min(want, _system_limit())
        if want > size:
            size = fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, want)
        return int(size)
    except (OSError, ValueError, AttributeError, ImportError):  # no descriptor (BytesIO), a user's
        return 0  # pipe quota used up (EPERM, EBUSY): read as the pipe is


def _system_limit() -> int:
    """The largest pipe an unprivileged process may ask for (Linux's default when unreadable)."""
    try:
        with open(PIPE_MAX, "rb") as f:
            return int(f.read().strip())
    except (OSError, ValueError):
        return 1 << 20


def waiting(f: IO[bytes]) -> bool:
    """Whether more of a pipe can be read at once: a fast writer's stream is taken in blocks, a
    live one as it comes."""
    try:
        import select

        return bool(select.select([f], [], [], 0)[0])
    except (OSError, ValueError, TypeError, AttributeError):  # not a file descriptor (a BytesIO)
        return False
