"""Records of real-time connections (port 30003/30013): one row per message, table `realtime`
(every version's columns in every file: `layout.all_columns`).

A real-time message has a size and no type; a controller sends every message of one
connection at the same size (its version's layout), so the connection is framed as
fixed records of that size: after a TCP gap the next boundary is known exactly, and a
capture begun mid-stream is cut where a size field equal to that size repeats.
Until then at most WINDOW bytes are held, each offset looked at once (a stream that
never shows a known size is passed over, counted and reported, in linear time).
"""

from __future__ import annotations

import re
from typing import Any

from rtde_spec.capture.framing.lines import FixedFraming, run_chunks, run_records
from rtde_spec.capture.protocols.base import Counts, server_port
from rtde_spec.capture.tables.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.errors import RtdeSpecError
from rtde_spec.realtime import decode, known_sizes, layout_for_size
from rtde_spec.realtime.layout import RealtimeLayout, all_columns

TABLE = "realtime"
SIZE = 4  # the size field leads each message
BATCH = 2048  # messages decoded together into columns
WINDOW = 64 << 10  # bytes held looking for the message size (a message is at most a few kB)
OPENING = 64  # the controller's first bytes kept: what they look like when no size is found


class RealtimeConnection:
    def __init__(self, name: str, robot: str, sink: TableSink) -> None:
        self.name, self.robot, self.sink = name, robot, sink
        sink.declare(TABLE, {"connection": "str", "capture_time": "f8", **all_columns()})
        self.counts = Counts()
        self.held: list[Chunk] = []  # chunks before the message size is known
        self.held_bytes = 0
        self.framing: dict[str, FixedFraming] = {}
        self.client_bytes = 0
        self.last_time = 0.0
        self.held_messages: list[bytes] = []
        self.held_times: list[float] = []
        self.search = bytearray()  # the held bytes, searched for the size
        self.searched = 0  # offsets of `search` already found to be no size (or unconfirmed)
        self.sizes = set(known_sizes())
        self.passed = 0  # bytes passed over without a known size
        self.opening = b""  # the controller's first bytes (another interface on this port?)

    def feed(self, sender: str, chunk: Chunk) -> None:
        self.last_time = chunk.time
        if sender == "client":  # clients send nothing the interface reads (URScript at most)
            self.client_bytes += len(chunk.data)
            return
        if "controller" not in self.framing:
            if len(self.opening) < OPENING:
                self.opening += chunk.data[: OPENING - len(self.opening)]
            self.held.append(chunk)
            self.held_bytes += len(chunk.data)
            self.search += chunk.data
            size = self._size(final=False)
            if size is None:
                self._bound()
                return
            self._start(size)
            return
        framing = self.framing["controller"]
        self._messages(framing.feed(chunk), chunk.time, framing.times)

    def feed_rows(self, sender: str, rows: Any, times: Any) -> bool:
        """Whole messages, one a segment in order (a run `bulk.runs` found: numpy rows), as `feed`
        takes them: straight to the messages once the size is known and the framing stands at a
        message boundary with nothing held, else a chunk a segment."""
        framing = self.framing.get("controller")
        when = times.tolist()
        if sender != "controller" or framing is None or not framing.at_boundary(rows.shape[1]):
            for chunk in run_chunks(rows, when):
                self.feed(sender, chunk)
            return True
        self.last_time = when[-1]
        self._messages(run_records(rows), when[-1], when)
        return True

    def _size(self, final: bool) -> int | None:
        """The connection's message size: a known size whose field repeats one message later.
        Offsets before `searched` were judged already; the search goes on from there."""
        data, sizes = self.search, self.sizes
        for at in range(self.searched, max(0, len(data) - SIZE + 1)):
            size = int.from_bytes(data[at : at + SIZE], "big")
            if size not in sizes:
                self.searched = at + 1
                continue
            if at + size + SIZE <= len(data):
                if data[at + size : at + size + SIZE] == data[at : at + SIZE]:
                    return size
                self.searched = at + 1
            elif not final:
                return None  # wait for the next message to confirm this one
            else:
                return size
        return None

    def _bound(self) -> None:
        """Past WINDOW bytes without a size: the bytes judged already are passed over (counted)."""
        if len(self.search) <= WINDOW or not self.searched:
            return
        drop = self.searched
        del self.search[:drop]
        self.searched = 0
        self.passed += drop
        self.held_bytes -= drop
        whole = 0  # the held chunks lose the same bytes from their front
        while whole < len(self.held) and len(self.held[whole].data) <= drop:
            drop -= len(self.held[whole].data)
            whole += 1
        del self.held[:whole]
        if drop and self.held:
            first = self.held[0]
            self.held[0] = Chunk(first.time, first.data[drop:], first.gap_before, first.midstream)

    def _start(self, size: int) -> None:
        marker = size.to_bytes(SIZE, "big")

        def plausible(buf: bytes, at: int) -> bool:
            return buf[at : at + SIZE] == marker

        framing = FixedFraming(size, plausible)
        self.framing["controller"] = framing
        held, self.held = self.held, []
        self.search = bytearray()
        for chunk in held:
            self._messages(framing.feed(chunk), chunk.time, framing.times)

    def _messages(self, messages: list[bytes], time: float, times: list[float] | None = None) -> None:
        """`times`: each message's, when not all `time` (the framing held some while it searched)."""
        self.counts.packages += len(messages)
        self.held_messages += messages
        self.held_times += times or [time] * len(messages)
        if len(self.held_messages) >= BATCH:
            self._flush()

    def _flush(self) -> None:
        """The held messages (all of the connection's size) as columns, by the layout's numpy plan;
        one by one where a field that carries a whole number does not."""
        raws, times = self.held_messages, self.held_times
        self.held_messages, self.held_times = [], []
        if not raws:
            return
        layout = layout_for_size(len(raws[0]))
        columns = _columns(layout, b"".join(raws)) if layout is not None else None
        if columns is not None:
            import numpy as np

            rows = {"connection": np.full(len(times), self.name), "capture_time": np.array(times), **columns}
            self.sink.columns(TABLE, self.robot, day_of(times[0]), rows)
            return
        for raw, time in zip(raws, times, strict=True):
            try:
                values = decode(raw)
            except RtdeSpecError as exc:
                self.counts.errors.append(f"message at {time:.6f}: {exc}")
                continue
            row = {"connection": self.name, "capture_time": time, **values}
            self.sink.row(TABLE, self.robot, day_of(time), row)

    def framings(self) -> dict[str, FixedFraming]:
        return self.framing

    def finish(self) -> None:
        size = self._size(final=True) if self.held else None
        if self.held and size is None:
            self.passed += self.held_bytes
            self.held = []
        if self.passed:
            self.counts.errors.append(
                f"{self.passed} bytes hold no real-time message of a known size{self._looks()}"
            )
        if size is not None:
            self._start(size)
        framing = self.framing.get("controller")
        if framing is not None:
            self._messages(framing.finish(), self.last_time, framing.times)
        self._flush()

    def close(self) -> None:
        self._flush()

    def _looks(self) -> str:
        """What the bytes look like when they are another interface's (a port moved, or mislabelled)."""
        from rtde_spec.capture.protocols.opening import content_kind

        kind = content_kind(self.opening)
        if kind is None or kind == "realtime":
            return ""
        port = server_port(self.name)
        return f"; they look like the {kind} interface: --port-map {port}={kind} decodes them as that"


def _columns(layout: RealtimeLayout, data: bytes) -> dict[str, Any] | None:
    """Columns of whole messages of one layout (its struct plan read as a numpy dtype)."""
    import numpy as np

    codes = re.findall(r"(\d*)([a-zA-Z?])", layout.plan.format.lstrip("<>!=@"))
    order = layout.plan.format[0] if layout.plan.format[0] in "<>!=@" else ">"
    kinds = [(int(n) if n else 1, np.dtype((">" if order == "!" else order) + c)) for n, c in codes]
    names = ("message_size", *layout.names)
    if len(codes) != len(names):
        return None
    dtype = np.dtype(
        [(name, k, (n,)) if n > 1 else (name, k) for name, (n, k) in zip(names, kinds, strict=True)]
    )
    if dtype.itemsize != layout.size:
        return None
    records = np.frombuffer(data, dtype=dtype)
    out: dict[str, Any] = {}
    for name in names:
        column = records[name].astype(records[name].dtype.newbyteorder("="))
        if name in layout.integers:
            if not np.all(np.isfinite(column)) or not np.all(column == np.round(column)):
                return None  # the one-by-one path says which message and field
            column = column.astype(np.int64)
        out[name] = column
    return out
