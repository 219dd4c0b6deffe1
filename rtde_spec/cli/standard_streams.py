"""The command's standard streams, made fit before it runs (the real command only: `entry`).

Closed ones get a stand-in, and standard output names itself when it fails: Python's own said
`[Errno 28] No space left on device` for `rtde-spec fields > /dev/full`, naming nothing.
"""

from __future__ import annotations

import errno
import io
import os
import sys

try:  # now: out of descriptors, an import then would fail too
    import fcntl
except ImportError:  # not POSIX
    fcntl = None  # type: ignore[assignment]

from rtde_spec.errors import OutputError

NO_ROOM = (errno.ENOSPC, errno.EDQUOT)


def set_up_streams() -> None:
    """Closed streams stood in for; standard output, if it is one, named in its write errors."""
    _stand_in_for_closed_streams()
    if getattr(sys.stdout, "closed_stream", False) or not isinstance(sys.stdout, io.TextIOWrapper):
        return
    try:
        if sys.stdout.fileno() != 1:
            return
    except (OSError, ValueError):
        return
    old = sys.stdout
    old.flush()
    raw = _StandardOutput()
    buffered = isinstance(old.buffer, io.BufferedWriter)  # not with PYTHONUNBUFFERED or -u
    sys.stdout = io.TextIOWrapper(
        io.BufferedWriter(raw) if buffered else raw,  # type: ignore[arg-type]
        encoding=old.encoding,
        errors=old.errors,
        line_buffering=old.line_buffering,  # a terminal's: each line as it is printed
        write_through=old.write_through,
    )


def discard_held_output() -> None:
    """Standard output's buffer dropped (it failed: a full disk), so that no later flush, Python's
    own at the end included, says it again."""
    sys.stdout = open(os.devnull, "w", encoding="utf-8")  # for the rest of the process


def output_failure() -> OSError | None:
    """The error a write to standard output raised, even where its caller swallowed it (argparse
    prints `--help` and ignores an OSError: unbuffered, the text was lost with exit 0)."""
    return _StandardOutput.failed


class _StandardOutput(io.RawIOBase):
    """Descriptor 1 as Python's standard output writes it, its full disk said as standard output's."""

    failed: OSError | None = None  # the first error of a write: one standard output a process

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return 1

    def isatty(self) -> bool:
        return os.isatty(1)

    def write(self, data: bytes) -> int | None:  # type: ignore[override]
        """All of `data` (unbuffered, this is `sys.stdout.buffer`: its callers write once)."""
        view, done = memoryview(data), 0
        try:
            while done < len(view):
                done += os.write(1, view[done:])
            return done
        except BlockingIOError:  # a non-blocking descriptor a parent left: as io.FileIO says it
            return done or None
        except OSError as exc:
            if exc.errno in NO_ROOM:
                said = "writing failed: the disk is full"
                exc = OutputError(said, errno=exc.errno, subject="standard output")
            if _StandardOutput.failed is None and not isinstance(exc, BrokenPipeError):
                _StandardOutput.failed = exc
            raise exc from None


def _stand_in_for_closed_streams() -> None:
    """Started with stdout or stderr closed (`>&-`), Python leaves `sys.stdout` None and every
    print failed with a traceback (a capture that had written all its tables exited 1), and the
    first file the command opened took descriptor 1 or 2, where a library's own messages would
    land in it. The closed descriptors get /dev/null; summaries and messages go nowhere, as to a
    closed terminal; data meant for standard output is refused by `output.writers.open_writer`
    (`closed_stream`), as it would be lost."""
    for fd, name in ((0, "stdin"), (1, "stdout"), (2, "stderr")):
        if not _usable(fd):
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:
                os.dup2(null, fd)
                os.close(null)
            if fd:  # the stream Python made of a file that took the descriptor: not ours to write
                setattr(sys, name, None)
        if getattr(sys, name) is None:
            stand_in = open(fd, "r" if fd == 0 else "w", encoding="utf-8", closefd=False)
            stand_in.closed_stream = True  # type: ignore[attr-defined]
            setattr(sys, name, stand_in)


def _usable(fd: int) -> bool:
    """Open, and for output not read-only: a closed stderr's descriptor can be a file a
    launcher opened (pyenv's shim script, read-only), and every message to it failed."""
    try:
        if fcntl is None:  # no access mode to read: open is all that is known
            os.fstat(fd)
            return True
        flags = fcntl.fcntl(fd, fcntl.F_GETFL)
    except OSError:
        return False
    return fd == 0 or flags & os.O_ACCMODE != os.O_RDONLY
