"""Records of real-time connections (port 30003/30013): one row per message, table `realtime`.

A real-time message has a size and no type; a controller sends every message of one
connection at the same size (its version's layout), so the connection is framed as
fixed records of that size: after a TCP gap the next boundary is known exactly, and a
capture begun mid-stream is cut where a size field equal to that size repeats.
"""

from __future__ import annotations

from rtde_spec.capture.connections import Counts
from rtde_spec.capture.records import FixedFraming
from rtde_spec.capture.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.errors import RtdeSpecError
from rtde_spec.realtime import decode, known_sizes

TABLE = "realtime"
SIZE = 4  # the size field leads each message


class RealtimeConnection:
    def __init__(self, name: str, robot: str, sink: TableSink) -> None:
        self.name, self.robot, self.sink = name, robot, sink
        self.counts = Counts()
        self.held: list[Chunk] = []  # chunks before the message size is known
        self.held_bytes = 0
        self.framing: dict[str, FixedFraming] = {}
        self.client_bytes = 0
        self.last_time = 0.0

    def feed(self, sender: str, chunk: Chunk) -> None:
        self.last_time = chunk.time
        if sender == "client":  # clients send nothing the interface reads (URScript at most)
            self.client_bytes += len(chunk.data)
            return
        if "controller" not in self.framing:
            self.held.append(chunk)
            self.held_bytes += len(chunk.data)
            size = self._size(b"".join(c.data for c in self.held), final=False)
            if size is None:
                return
            self._start(size)
            return
        self._messages(self.framing["controller"].feed(chunk), chunk.time)

    def _size(self, data: bytes, final: bool) -> int | None:
        """The connection's message size: a known size whose field repeats one message later."""
        sizes = set(known_sizes())
        for at in range(max(0, len(data) - SIZE + 1)):
            size = int.from_bytes(data[at : at + SIZE], "big")
            if size not in sizes:
                continue
            if at + size + SIZE <= len(data):
                if data[at + size : at + size + SIZE] == data[at : at + SIZE]:
                    return size
            elif not final:
                return None  # wait for the next message to confirm this one
            else:
                return size
        return None

    def _start(self, size: int) -> None:
        marker = size.to_bytes(SIZE, "big")

        def plausible(buf: bytes, at: int) -> bool:
            return buf[at : at + SIZE] == marker

        framing = FixedFraming(size, plausible)
        self.framing["controller"] = framing
        held, self.held = self.held, []
        for chunk in held:
            self._messages(framing.feed(chunk), chunk.time)

    def _messages(self, messages: list[bytes], time: float) -> None:
        for raw in messages:
            self.counts.packages += 1
            try:
                values = decode(raw)
            except RtdeSpecError as exc:
                self.counts.errors.append(f"message at {time:.6f}: {exc}")
                continue
            self.sink.row(
                TABLE, self.robot, day_of(time), {"connection": self.name, "capture_time": time, **values}
            )

    def framings(self) -> dict[str, FixedFraming]:
        return self.framing

    def finish(self) -> None:
        if self.held:
            size = self._size(b"".join(c.data for c in self.held), final=True)
            if size is None:
                self.counts.errors.append(
                    f"{self.held_bytes} bytes hold no real-time message of a known size"
                )
                self.held = []
            else:
                self._start(size)
        framing = self.framing.get("controller")
        if framing is not None:
            self._messages(framing.finish(), self.last_time)

    def close(self) -> None:
        pass
