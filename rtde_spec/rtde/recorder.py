"""Recording a controller's outputs to a file, through the streaming writers.

Data packages come from the client's reader thread as numpy arrays, one per read of
the socket (`RtdeClient.on_batch`: no Python object per package), so recording keeps
up at 500 Hz; the file is flushed batch by batch (handed to the operating system, so a
killed process loses at most the batch being collected), and whatever arrived before
Ctrl-C, a `stop` event (the CLI sets it on SIGTERM and SIGHUP) or a dropped connection
is written and the file closed readable.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from rtde_spec.errors import require
from rtde_spec.output.base import Writer
from rtde_spec.rtde.client import RtdeClient

BATCH_SECONDS = 0.2
LATE_SECONDS = 1.0  # how long past --duration to wait for packages the controller still owes


class StopSignal(Protocol):
    """Anything that says whether to stop: a threading.Event, or a flag a signal handler sets."""

    def is_set(self) -> bool: ...


@dataclass
class RecordResult:
    rows: int
    seconds: float
    skipped: int
    stopped_by: str  # "duration", "samples", "interrupt", "stop" (the event), "connection"


def record(
    client: RtdeClient,
    names: Sequence[str],
    frequency: float,
    writer: Writer,
    *,
    duration: float | None = None,
    samples: int | None = None,
    progress: Callable[[int], None] | None = None,
    stop: StopSignal | None = None,
) -> RecordResult:
    """Set up `names`, start, and write rows until the duration or sample count is reached,
    Ctrl-C, or `stop` is set (a `threading.Event` from another thread; the CLI's signal
    handlers set a plain flag, as taking the Event's lock inside a handler could deadlock)."""
    numpy = require("numpy", "numpy", "recording")
    codec = client.setup_outputs(names, frequency)
    pending: list[Any] = []  # numpy arrays, one per read of the socket
    lock = threading.Lock()

    def collect(array: Any) -> None:
        with lock:
            pending.append(array)

    client.on_batch(collect)
    client.start()
    start = time.monotonic()
    rows, stopped_by = 0, "duration"
    # a duration is the controller's time: its packages come `frequency` a second, so S seconds
    # are S x frequency rows (checking the clock once a batch would overshoot by up to a batch)
    by_duration = max(1, round(duration * frequency)) if duration is not None else None
    limits = [n for n in (samples, by_duration) if n is not None]
    limit = min(limits) if limits else None

    def flush() -> int:
        nonlocal pending
        with lock:
            batch, pending = pending, []
        if not batch:
            return 0
        array = batch[0] if len(batch) == 1 else numpy.concatenate(batch)
        if limit is not None:
            array = array[: max(0, limit - rows)]
        if not len(array):
            return 0
        writer.write_columns({name: array[name] for name in codec.names})
        writer.flush()
        if progress is not None:
            progress(len(array))
        return len(array)

    try:
        while True:
            time.sleep(BATCH_SECONDS)
            rows += flush()
            if stop is not None and stop.is_set():
                stopped_by = "stop"
                break
            if limit is not None and rows >= limit:
                stopped_by = "samples" if limit == samples else "duration"
                break
            if duration is not None and time.monotonic() - start >= duration + LATE_SECONDS:
                break  # the controller sent fewer packages than its rate promises: stop anyway
            if client.connection_lost is not None:
                stopped_by = "connection"
                break
    except KeyboardInterrupt:
        stopped_by = "interrupt"
    finally:
        rows += flush()
    if stopped_by != "connection":
        try:
            client.pause()
        except Exception:
            pass
    return RecordResult(rows, time.monotonic() - start, client.skipped, stopped_by)
