"""Records of URCL's external-control connections: reverse, trajectory and script command
records to one row each, the script sender's exchange to one row per program request.

On these ports the driver's PC is the server and the robot the client, so the robot
(the partition of every row) is the client's address. Variants of one message that
share a table keep the fields they share as columns; the rest of each row goes to an
`arguments` column as JSON (the script commands: each has its own arguments).

A message URCL versions send in different layouts (the trajectory point) is held, as
it arrived, until its layout is chosen (external/layouts.py): at its first bytes when
the program its robot was sent before the connection names one (the usual order of a
session), else at the end of the capture. The programs are those of the same capture
file (`session`, shared by its connections), so the choice depends on the file alone,
not on the order files are decoded in; the connection's `notes` say what was chosen.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from rtde_spec.capture.framing.lines import FixedFraming, run_chunks, run_records
from rtde_spec.capture.protocols.base import Counts, server_port
from rtde_spec.capture.tables.rows import text_columns
from rtde_spec.capture.tables.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.errors import RtdeSpecError
from rtde_spec.external.codec import RecordCodec, VariantPlan, protocol_codecs, record_codec
from rtde_spec.external.layouts import Choice, LayoutChooser
from rtde_spec.external.programs import MAX_PROGRAM_BYTES, programs_of
from rtde_spec.metamodel.external import ExternalProtocol
from rtde_spec.output.base import plain
from rtde_spec.wire.columns import decode_columns, record_dtype

SIDE = {"client": "robot", "controller": "driver"}  # the flow's sender names on a driver-served port
MAX_SCRIPT = MAX_PROGRAM_BYTES
BATCH = 4096  # records of one variant decoded together into columns
MAX_LINE = 4096  # a robot's request line is a word or two: longer ones are cut, counted and reported
MAX_REQUESTS = 1000  # requests kept per connection (the robot asks once per program start)
MAX_HELD = 4 << 20  # bytes held waiting for a layout; past that it is chosen from what is known
CHUNK_COST = 128  # what holding one chunk costs beside its bytes: 1-byte segments count that much


def _shared(codec: RecordCodec) -> dict[str, list[str] | None]:
    """variant name -> the columns its table shares with the other variants there (None: all its own)."""
    tables: dict[str, list[VariantPlan]] = {}
    for plan in codec.variants:
        tables.setdefault(plan.table, []).append(plan)
    out: dict[str, list[str] | None] = {}
    for plans in tables.values():
        if len(plans) == 1:
            out[plans[0].name] = None
            continue
        common = [n for n in plans[0].layout.names if all(n in p.layout.names for p in plans)]
        for plan in plans:
            out[plan.name] = common
    return out


class ExternalConnection:
    """A reverse, trajectory or script command connection: fixed records both ways."""

    def __init__(
        self,
        name: str,
        robot: str,
        sink: TableSink,
        protocol: ExternalProtocol,
        session: dict[str, Any] | None = None,
    ) -> None:
        self.name, self.robot, self.sink, self.protocol = name, robot, sink, protocol
        self.codecs = protocol_codecs(protocol)
        self.framing = {
            sender: FixedFraming(c.size, c.plausible)
            for sender, side in SIDE.items()
            if (c := self.codecs.get(side)) is not None
        }
        self.shared = {side: _shared(c) for side, c in self.codecs.items()}
        self.counts = Counts()
        self.unexpected: dict[str, int] = {}
        self.last_time = 0.0
        self.start: float | None = None  # capture time of the connection's first bytes
        self.batches: dict[str, tuple[VariantPlan, Any, list[bytes], list[float]]] = {}
        programs = programs_of(session)
        self.choosers = {  # sender -> the chooser of its message's layout, until chosen
            sender: LayoutChooser(protocol.name, m, robot, programs)
            for sender, side in SIDE.items()
            for m in protocol.messages
            if m.sender == side and m.older
        }
        self.held: dict[str, list[Chunk]] = {sender: [] for sender in self.choosers}
        self.held_bytes = 0
        self.notes: list[str] = []  # what was chosen, and why: the summary shows them

    def feed(self, sender: str, chunk: Chunk) -> None:
        self.last_time = chunk.time
        self.start = chunk.time if self.start is None else self.start
        framing = self.framing.get(sender)
        if framing is None:  # this side sends nothing in the protocol
            self.unexpected[sender] = self.unexpected.get(sender, 0) + len(chunk.data)
            return
        if sender in self.choosers:
            held = self.held[sender]
            held.append(chunk)
            self.held_bytes += len(chunk.data) + CHUNK_COST
            if len(held) == 1 or self.held_bytes > MAX_HELD:  # the program sent before, else the end decides
                self._choose(sender, final=self.held_bytes > MAX_HELD)
            return
        self._records(SIDE[sender], framing.feed(chunk), chunk.time, framing.times)

    def feed_rows(self, sender: str, rows: Any, times: Any) -> bool:
        """Whole records, one a segment in order (a run `bulk.runs` found: numpy rows), as `feed`
        decodes them: straight to the records when the layout is chosen and the framing stands at
        a record boundary with nothing held, else as one chunk a segment (what TCP reassembly
        gives for segments in order)."""
        framing = self.framing.get(sender)
        when = times.tolist()
        if (
            sender in self.choosers
            or not isinstance(framing, FixedFraming)
            or not framing.at_boundary(rows.shape[1])
        ):
            for chunk in run_chunks(rows, when):
                self.feed(sender, chunk)
            return True
        self.last_time = when[-1]
        self.start = when[0] if self.start is None else self.start
        self._records(SIDE[sender], run_records(rows), when[-1], when)
        return True

    def _choose(self, sender: str, final: bool) -> None:
        """Choose the layout of what `sender` sends if its program (or, when `final`, anything) says;
        then decode what was held as if it had been known from the first byte."""
        held = self.held[sender]
        if not held:
            return
        choice = self.choosers[sender].choose(self.start or 0.0, [c.data for c in held], final)
        if choice is not None:
            self._use(sender, choice)

    def _use(self, sender: str, choice: Choice) -> None:
        side, chooser = SIDE[sender], self.choosers.pop(sender)
        codec = record_codec(self.protocol.name, chooser.message.name, choice.layout)
        self.codecs[side], self.shared[side] = codec, _shared(codec)
        framing = self.framing[sender] = FixedFraming(codec.size, codec.plausible)
        self.notes.append(f"{self.protocol.name} layout {choice.name} ({choice.why})")
        for chunk in self.held.pop(sender):
            self._records(side, framing.feed(chunk), chunk.time, framing.times)

    def _records(self, side: str, records: list[bytes], now: float, times: list[float] | None = None) -> None:
        """`times`: each record's, when not all `now` (the framing held some while it searched)."""
        codec, shared = self.codecs[side], self.shared[side]
        today = day_of(now)
        for record, time in zip(records, times or [now] * len(records), strict=True):
            day = today if time == now else day_of(time)
            self.counts.packages += 1
            plan = codec.variant_of(record)
            if (
                plan is not None and shared[plan.name] is None
            ):  # a table of its own: decoded later, many at once
                self._hold(plan, record, time)
                continue
            try:
                plan, values = codec.decode(record)
            except RtdeSpecError as exc:
                self.counts.errors.append(f"{side} record at {time:.6f}: {exc}")
                continue
            common = shared[plan.name]
            assert common is not None
            row: dict[str, Any] = {"connection": self.name, "capture_time": time}
            row.update({n: values[n] for n in common})
            row["variant"] = plan.name
            row["arguments"] = json.dumps(plain({n: v for n, v in values.items() if n not in common}))
            self.sink.row(plan.table, self.robot, day, row)

    def _hold(self, plan: VariantPlan, record: bytes, time: float) -> None:
        batch = self.batches.get(plan.name)
        if batch is None:
            dtype = record_dtype(plan.spec.fields, plan.layout.prims, plan.layout.order, len(record))
            batch = self.batches[plan.name] = (plan, dtype, [], [])
        batch[2].append(record)
        batch[3].append(time)
        if len(batch[2]) >= BATCH:
            self._flush(plan.name)

    def _flush(self, name: str) -> None:
        batch = self.batches.pop(name, None)
        if batch is None or not batch[2]:
            return
        import numpy as np

        plan, dtype, records, times = batch
        columns: dict[str, Any] = {
            "connection": np.full(len(times), self.name),
            "capture_time": np.array(times),
            **decode_columns(b"".join(records), dtype, plan.spec.fields),
        }
        self.sink.columns(plan.table, self.robot, day_of(times[0]), columns)

    def framings(self) -> dict[str, FixedFraming]:
        return self.framing

    def finish(self) -> None:
        for sender in list(self.choosers):
            self._choose(sender, final=True)
        for sender, framing in self.framing.items():
            self._records(SIDE[sender], framing.finish(), self.last_time, framing.times)
            if framing.unaligned:
                self.counts.errors.append(
                    f"{SIDE[sender]}: no record boundary found; decoded from the first byte"
                )
        self.close()
        for sender, count in self.unexpected.items():
            self.counts.errors.append(
                f"{count} bytes from the {SIDE[sender]}, which sends nothing on this port"
            )

    def close(self) -> None:
        for sender in list(self.choosers):  # an interrupted capture: what was held reaches the tables
            self._choose(sender, final=True)
        for name in list(self.batches):
            self._flush(name)


@dataclass
class _Request:
    time: float
    line: str
    reply: bytearray = field(default_factory=bytearray)
    reply_time: float | None = None
    last_time: float | None = None
    gaps: int = 0
    dropped: int = 0


class ScriptSenderConnection:
    """The script sender: the robot's request line, then the driver's program text, one row each."""

    def __init__(
        self,
        name: str,
        robot: str,
        sink: TableSink,
        protocol: ExternalProtocol,
        session: dict[str, Any] | None = None,
    ) -> None:
        self.name, self.robot, self.sink, self.table = name, robot, sink, protocol.table or protocol.name
        self.request = (protocol.request or "").rstrip("\n").encode()
        self.framing = {"client": _NoFraming(), "controller": _NoFraming()}
        self.pending = bytearray()
        self.requests: list[_Request] = []
        self.counts = Counts()
        self.programs = programs_of(session)
        self.port = server_port(name)  # the server's (driver's) port
        self.extra_requests = 0  # requests past MAX_REQUESTS: counted, not kept
        self.over = 0  # bytes of replies to those
        self.cut_bytes = 0  # bytes of robot lines past MAX_LINE

    def _new(self, request: _Request) -> None:
        """A request (a row at the end); past MAX_REQUESTS only counted: memory stays bounded."""
        if len(self.requests) >= MAX_REQUESTS:
            self.extra_requests += 1
            return
        self.requests.append(request)
        if self.programs is not None:  # the text grows in place: readers see what has arrived
            self.programs.add(self.robot, self.port, request)

    def feed(self, sender: str, chunk: Chunk) -> None:
        if sender == "client":
            self._lines(chunk)
            return
        if not self.requests:  # text before any request (a capture started late)
            self._new(_Request(chunk.time, ""))
        if self.extra_requests:  # replies to requests past the bound: counted
            self.over += len(chunk.data)
            return
        current = self.requests[-1]
        current.gaps += 1 if chunk.gap_before else 0
        current.reply_time = current.reply_time if current.reply_time is not None else chunk.time
        current.last_time = chunk.time
        room = MAX_SCRIPT - len(current.reply)
        current.reply += chunk.data[:room]
        current.dropped += max(0, len(chunk.data) - room)

    def _lines(self, chunk: Chunk) -> None:
        """The robot's request lines: each new byte looked at once; a line is at most MAX_LINE."""
        data, pos = chunk.data, 0
        if self.extra_requests:  # past the bound: lines are only counted, all of this chunk's at once
            lines = data.count(b"\n")
            if lines:
                self.counts.packages += lines
                self.extra_requests += lines
                self.pending.clear()
                pos = data.rindex(b"\n") + 1
        while (end := data.find(b"\n", pos)) != -1:
            piece = data[pos : min(end, pos + MAX_LINE - len(self.pending))]
            line = bytes(self.pending) + piece if self.pending else bytes(piece)
            self.cut_bytes += (end - pos) - len(piece)
            self.pending.clear()
            pos = end + 1
            self.counts.packages += 1
            self._new(_Request(chunk.time, line.decode("utf-8", "replace")))
            if line != self.request:
                self.counts.errors.append(
                    f"robot line at {chunk.time:.6f} is not a program request: {line[:60]!r}"
                )
        rest = data[pos:]
        room = max(0, MAX_LINE - len(self.pending))
        self.pending += rest[:room]
        self.cut_bytes += len(rest) - min(room, len(rest))

    def framings(self) -> dict[str, _NoFraming]:
        return self.framing

    def finish(self) -> None:
        bounds = []  # first in the list: never lost among a flood's own problems
        if self.pending:
            bounds.append(f"the robot's last line has no end ({len(self.pending)} bytes)")
        if self.cut_bytes:
            bounds.append(f"{self.cut_bytes} bytes of robot lines over {MAX_LINE} bytes cut")
        if self.extra_requests or self.over:
            bounds.append(
                f"{self.extra_requests} requests past the first {MAX_REQUESTS} of this connection "
                f"counted, not kept ({self.over} bytes of their replies)"
            )
        self.counts.errors[:0] = bounds
        for req in self.requests:
            latency = req.reply_time - req.time if req.reply_time is not None and req.line else None
            row = {
                "connection": self.name,
                "capture_time": req.time,
                "request": req.line,
                **text_columns("script", bytes(req.reply)),
                "script_bytes": len(req.reply) + req.dropped,
                "reply_time": req.reply_time if req.reply_time is not None else float("nan"),
                "latency": latency if latency is not None else float("nan"),
                "complete": not req.gaps and not req.dropped,
            }
            self.sink.row(self.table, self.robot, day_of(req.time), row)
            if req.gaps or req.dropped:
                self.counts.errors.append(
                    f"program sent at {req.time:.6f}: {req.gaps} gaps in its text, "
                    f"{req.dropped} bytes over {MAX_SCRIPT}"
                )
        self.requests.clear()

    def close(self) -> None:
        pass


class _NoFraming:
    """The script sender needs no framing; the summary's attributes, all zero."""

    def __init__(self) -> None:
        self.buf = bytearray()
        self.skipped = self.cut = self.lead_in = 0
