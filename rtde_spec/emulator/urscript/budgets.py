"""A program's budgets: the interpreter's time in a control step, each thread's share of it, and
the process's memory.

The server computes a step's state just before the step is due and sends it at the due time
(server/loop.py), so a step's program has the time left until then: `step_deadline(until)` says when
that is, for the steps computed inside it. A program run without one (a model stepped by hand,
a program's first run when it arrives) has SLICE of a step. Either way a program always has
SLICE of a step in CPU time, so a loaded machine slows a program down but does not change
what it does.

The threads share the time round robin, as the Script Manual schedules them: each thread in
turn has an equal share of what is left, so a thread that waits early leaves its time to the
ones after it, and one that never waits (a loop reading a flood of socket messages) cannot take
the step from the threads that move the arm. Threads preempted at the end of their share go
on in the same step while time is left.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

SLICE = 0.3  # of a control step: the interpreter's CPU time in it, whatever the deadline

__all__ = ["SLICE", "Budget", "StepWork", "resident_bytes", "step_deadline"]


@dataclass
class StepWork:
    """One control step's work: when it must end, and whether a program wanted more time."""

    until: float  # time.perf_counter(): the step is sent then, its programs' work ends before
    cut: bool = False  # a thread was preempted: the next step's work should start earlier


_CURRENT = threading.local()  # the step being computed in this thread (each emulator has its own)


@contextmanager
def step_deadline(until: float) -> Iterator[StepWork]:
    """The programs stepped inside end their work by `until` (a time.perf_counter() value)."""
    work, previous = StepWork(until), getattr(_CURRENT, "work", None)
    _CURRENT.work = work
    try:
        yield work
    finally:
        _CURRENT.work = previous


class Budget:
    """One program's time in one control step: a wall-clock end and a CPU-time floor."""

    def __init__(self, step_seconds: float) -> None:
        now, cpu = time.perf_counter(), time.thread_time()
        self.work: StepWork | None = getattr(_CURRENT, "work", None)
        self.wall_end = self.work.until if self.work is not None else now + SLICE * step_seconds
        self.cpu_end = cpu + SLICE * step_seconds

    def share(self, runnable: int) -> tuple[float, float]:
        """(wall-clock end, CPU-time end) for the next of `runnable` threads still to run."""
        now, cpu = time.perf_counter(), time.thread_time()
        return (
            now + max(0.0, self.wall_end - now) / runnable,
            cpu + max(0.0, self.cpu_end - cpu) / runnable,
        )

    def left(self) -> bool:
        """Whether any of the step's time is left (wall clock or CPU floor)."""
        return time.perf_counter() < self.wall_end or time.thread_time() < self.cpu_end

    def preempted(self) -> None:
        """A thread is still preempted at the step's end: the server starts the next step earlier."""
        if self.work is not None:
            self.work.cut = True


def resident_bytes() -> int:
    """The process's resident memory (Linux /proc; elsewhere 0: the memory budget is not kept)."""
    try:
        if not _STATM:
            _STATM.append(os.open("/proc/self/statm", os.O_RDONLY | getattr(os, "O_CLOEXEC", 0)))
        return int(os.pread(_STATM[0], 128, 0).split()[1]) * _PAGE
    except (OSError, ValueError, IndexError, AttributeError):
        return 0


_STATM: list[int] = []  # /proc/self/statm, opened once (read in a few µs, not opened each time)
_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
