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
SHARE = 0.5  # of the time since the last look, on a core or waiting for one
LEAST = 0.5  # seconds on a core or waiting for one
LAST_LOOK = 0.3  # s the threads the last module left are watched at the session's end


def thread_busy() -> dict[int, tuple[float, float]]:
    """(CPU s, CPU s + s waiting for a core) of each thread of this process, by native id: a
    spinning thread is always one or the other, whatever else the machine runs (schedstat;
    without it, CPU ticks from stat, which a loaded machine shares out)."""
    busy = {}
    for task in TASKS.iterdir() if TASKS.is_dir() else ():
        try:
            cpu_ns, queued_ns, _ = (task / "schedstat").read_text().split()
            busy[int(task.name)] = (int(cpu_ns) / 1e9, (int(cpu_ns) + int(queued_ns)) / 1e9)
            continue
        except (OSError, ValueError):  # ended meanwhile, or no schedstat: the ticks
            pass
        try:
            fields = (task / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        cpu = (int(fields[11]) + int(fields[12])) / TICK
        busy[int(task.name)] = (cpu, cpu)
    return busy


class ThreadWatch:
    """The threads alive at the last look, with their CPU then; one per test process (`WATCH`)."""

    def __init__(self) -> None:
        self.seen: dict[int, tuple[str, tuple[float, float], float]] = {}  # id -> (module, busy, when)

    def spinning_after(self, module: str, least: float = LEAST) -> list[str]:
        """At `module`'s end: the threads left busy since the last look (on a core or waiting for
        one over `SHARE` of the time and `least` s), described; then look again."""
        now, busy = time.monotonic(), thread_busy()
        alive = {t.native_id: t for t in threading.enumerate() if t is not threading.main_thread()}
        found = []
        for tid, (left_by, (cpu, runnable), then) in self.seen.items():
            if tid in alive and tid in busy:
                used, wanted = busy[tid][0] - cpu, busy[tid][1] - runnable
                if wanted > least and wanted > SHARE * (now - then):
                    found.append(
                        f"thread {alive[tid].name!r}, alive since {left_by} ended, used {used:.1f} s of "
                        f"CPU (and waited {wanted - used:.1f} s for a core) in the {now - then:.1f} s since"
                    )
        self.seen = {tid: (module, busy.get(tid, (0.0, 0.0)), now) for tid in alive if tid is not None}
        return found

    def spinning_at_the_end(self, look: float = LAST_LOOK) -> list[str]:
        """At the session's end (after the last module's own look): the threads the last module
        left, watched for `look` s, when it left any."""
        if not self.seen:
            return []
        time.sleep(look)
        return self.spinning_after("the session", least=SHARE * look)


WATCH = ThreadWatch()
