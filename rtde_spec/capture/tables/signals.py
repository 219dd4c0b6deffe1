"""Signals held off while a capture's tables are put in place or dropped.

A second Ctrl-C (or a SIGTERM) in the middle of renaming a capture's tables into place, or
of removing its temp files, would leave some tables of this run beside some of the last,
or hidden temp files for good: those few file operations run to their end first.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


@contextmanager
def signals_held(replay: bool = True) -> Iterator[None]:
    """Ctrl-C, SIGTERM and SIGHUP held for the block (the main thread only: elsewhere no
    signal handler runs anyway), then as they were; one that came is then raised as
    KeyboardInterrupt (`replay`), or dropped when the block is already a stop's clean-up."""
    came: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        came.append(signum)

    names = [n for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)]
    held: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        held = {getattr(signal, n): signal.signal(getattr(signal, n), hold) for n in names}
    try:
        yield
    finally:
        for signum, handler in held.items():
            signal.signal(signum, handler)
    if came and replay:
        raise KeyboardInterrupt
