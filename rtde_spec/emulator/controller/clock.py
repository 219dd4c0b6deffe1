"""The control loop's wake-up: at each step's due time, to a fraction of a millisecond.

asyncio sleeps through `epoll_wait`, whose timeout is whole milliseconds rounded up, so a
step woken by `asyncio.sleep` is up to 1 ms late unless the loop spins for the rest (which
costs a loaded machine a third of a core at 500 Hz). On Linux a `timerfd` armed at the
absolute due time (CLOCK_MONOTONIC, the clock `time.perf_counter` reads) makes the loop's
own `epoll_wait` return at that time, to the kernel's timer precision, with no spinning and
no extra thread. Elsewhere (or if the timerfd cannot be made) the old way stays: sleep to
just before the due time, then spin with `time.sleep(0)`.
"""

from __future__ import annotations

import asyncio
import ctypes
import ctypes.util
import os
import sys
import time

SPIN_SECONDS = 0.0008  # the fallback's last part of each wait, spent awake
_CLOCK_MONOTONIC = 1
_TFD_TIMER_ABSTIME = 1
_TFD_NONBLOCK = os.O_NONBLOCK
_TFD_CLOEXEC = 0o2000000


class _Timespec(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


class _Itimerspec(ctypes.Structure):
    _fields_ = [("it_interval", _Timespec), ("it_value", _Timespec)]


def _libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux") or time.get_clock_info("perf_counter").implementation != (
        "clock_gettime(CLOCK_MONOTONIC)"
    ):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        libc.timerfd_create.argtypes = [ctypes.c_int, ctypes.c_int]
        libc.timerfd_settime.argtypes = [
            ctypes.c_int, ctypes.c_int, ctypes.POINTER(_Itimerspec), ctypes.c_void_p,
        ]  # fmt: skip
        return libc
    except (OSError, AttributeError):
        return None


class StepClock:
    """`await clock.until(due)`: return at `due` (a `time.perf_counter()` value), not before."""

    def __init__(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._fd = -1
        self._waiter: asyncio.Future[None] | None = None
        self._libc: ctypes.CDLL | None = None
        libc = _libc()
        if libc is not None:
            fd = libc.timerfd_create(_CLOCK_MONOTONIC, _TFD_NONBLOCK | _TFD_CLOEXEC)
            if fd >= 0:
                self._libc, self._fd = libc, fd
                self._loop.add_reader(fd, self._fired)
        self.precise = self._fd >= 0  # False: the sleep-and-spin fallback

    async def until(self, due: float) -> None:
        if self._fd < 0 or self._libc is None:
            await self._sleep_and_spin(due)
            return
        if due <= time.perf_counter():
            return
        seconds = int(due)
        spec = _Itimerspec(_Timespec(0, 0), _Timespec(seconds, int((due - seconds) * 1e9)))
        if self._libc.timerfd_settime(self._fd, _TFD_TIMER_ABSTIME, ctypes.byref(spec), None) != 0:
            await self._sleep_and_spin(due)  # never seen; the loop goes on the old way
            return
        self._waiter = self._loop.create_future()
        try:
            await self._waiter
        finally:
            self._waiter = None
        while time.perf_counter() < due:  # the kernel fired a hair early (never seen): wait it out
            time.sleep(0)

    def _fired(self) -> None:
        try:
            os.read(self._fd, 8)
        except (BlockingIOError, InterruptedError):
            return
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)

    @staticmethod
    async def _sleep_and_spin(due: float) -> None:
        delay = due - time.perf_counter()
        if delay > SPIN_SECONDS:
            await asyncio.sleep(delay - SPIN_SECONDS)
        while time.perf_counter() < due:
            time.sleep(0)  # stay awake, but let other threads (an in-process client) run

    def close(self) -> None:
        if self._fd >= 0:
            self._loop.remove_reader(self._fd)
            os.close(self._fd)
            self._fd = -1
