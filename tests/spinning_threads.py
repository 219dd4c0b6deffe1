"""Threads a test module leaves running, busy, in the test process: found one module later.

A client library's thread that outlives its test and spins (python-urx's real-time monitor
calls recv() for ever once the stream ends) takes a core and the GIL from every later test of
its xdist worker: 132 s of CPU in one whole run, and timing tests that failed for no reason
of their own. At each module's end the threads alive at the previous module's end that used
more than half a core since (and over half a second) are named, with the module that left
them; the check costs a read of /proc, no waiting. Linux only (elsewhere it does nothing).
"""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

TASKS = Path("/proc/self/task")
TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
SHARE = 0.5  # of a core, on average since the last look
LEAST = 0.5  # seconds of CPU

_seen: dict[int, tuple[str, int, float]] = {}  # native id -> (module it outlived, ticks, when)


def thread_ticks() -> dict[int, int]:
    """CPU ticks (user + system) of each thread of this process, by native id."""
    ticks = {}
    for task in TASKS.iterdir() if TASKS.is_dir() else ():
        try:
            fields = (task / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        ticks[int(task.name)] = int(fields[11]) + int(fields[12])
    return ticks


def spinning_after(module: str) -> list[str]:
    """At `module`'s end: the threads left busy since the last look, described; then look again."""
    now, ticks = time.monotonic(), thread_ticks()
    alive = {t.native_id: t for t in threading.enumerate() if t is not threading.main_thread()}
    found = []
    for tid, (left_by, before, then) in _seen.items():
        if tid in alive and tid in ticks:
            used = (ticks[tid] - before) / TICK
            if used > LEAST and used > SHARE * (now - then):
                found.append(
                    f"thread {alive[tid].name!r}, alive since {left_by} ended, used {used:.1f} s "
                    f"of CPU in the {now - then:.1f} s since"
                )
    _seen.clear()
    _seen.update({tid: (module, ticks.get(tid, 0), now) for tid in alive if tid is not None})
    return found
