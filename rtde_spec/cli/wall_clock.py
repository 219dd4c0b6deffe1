"""`record --wall-clock`: the host's receive time of each row, as a column `host_time` beside the
controller's `timestamp` (seconds since the epoch, float64).

The client's reader thread notes `time.time()` as each data package is handed over (packages of
one socket read share that time). A row's host_time is its read's time moved earlier by how
much sooner the controller stamped it than the last package read with or after it in the same
batch: host_time[i] = timestamp[i] + min over j >= i of (read_time[j] - timestamp[j]). So the
spacing of host_time follows the controller's timestamp (never backwards, never bunched by
reads), and the newest row of each batch carries its read's time exactly. Without `timestamp`
in the recipe, host_time is the read time itself.
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Mapping
from typing import Any

COLUMN = "host_time"


class ReceiveTimes:
    """An `on_batch` callback that notes when each read's data packages arrived; register it
    before the recorder's own (callbacks of one kind run in the order added), so a package's
    time is noted before the recorder can write it."""

    def __init__(self) -> None:
        self.times: deque[float] = deque()

    def __call__(self, packages: Any) -> None:
        self.times.extend(itertools.repeat(time.time(), len(packages)))

    def take(self, count: int) -> list[float]:
        times = self.times
        return [times.popleft() if times else time.time() for _ in range(count)]


class WallClockWriter:
    """A writer that adds `host_time` after `timestamp` (first when there is none) to every batch
    of columns and hands everything else to the writer it wraps."""

    def __init__(self, writer: Any, received: ReceiveTimes) -> None:
        self._writer = writer
        self._received = received

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        import numpy as np

        count = len(next(iter(columns.values()))) if columns else 0
        read = np.array(self._received.take(count), dtype=np.float64)
        stamp = columns.get("timestamp")
        if stamp is not None and count:
            stamp = np.asarray(stamp, dtype=np.float64)
            lead = np.minimum.accumulate((read - stamp)[::-1])[::-1]
            host = stamp + lead
        else:
            host = read
        out: dict[str, Any] = {} if "timestamp" in columns else {COLUMN: host}
        for name, column in columns.items():
            out[name] = column
            if name == "timestamp":
                out[COLUMN] = host
        self._writer.write_columns(out)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._writer, name)
