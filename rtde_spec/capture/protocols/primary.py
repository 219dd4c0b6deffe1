"""Primary/secondary connections of a capture: the controller's messages to one table per sub-package.

What the client sends is URScript (kept as text, and as the robot's program when a driver
in headless mode sends it here). A resynchronisation candidate of a family made of
sub-packages is sure when their sizes fill it. The Version message (the first one the
controller sends) picks the spec's older layouts for what follows, as a stream decoder's
does; why values may still be wrong (`primary/version_warnings.py`) goes into the
connection's notes once each, and a message of a type the spec does not know keeps its
family, type and prefix beside its bytes.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any

from rtde_spec.capture.framing.sized import STRONG, WEAK, Check, Framing
from rtde_spec.capture.protocols.base import Counts, server_port
from rtde_spec.capture.tables.rows import column_types, flatten_part, text_columns
from rtde_spec.capture.tables.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.errors import RtdeSpecError
from rtde_spec.external.programs import MAX_PROGRAM_BYTES, ProgramSent, programs_of
from rtde_spec.output.base import plain

if TYPE_CHECKING:
    from rtde_spec.metamodel.versions import Version
    from rtde_spec.primary.robot_state import Reuse

MAX_NOTES = 20  # distinct warnings kept per connection (each is said once, whatever the count)
SCRIPT_PAUSE = 0.05  # s between a client's sends that ends a row of primary_scripts (one send: ~µs)
MAX_SCRIPT_ROW = 4 << 20  # bytes of one row at most (URCL's program is 50 kB)
NO_VERSION = (
    "no Version message before it in the capture (decoded with the newest layouts; "
    "capture --controller VERSION gives the robot's)"
)


class PrimaryConnection:
    def __init__(self, name: str, robot: str, sink: TableSink, session: dict[str, Any] | None = None) -> None:
        from rtde_spec.primary.codec import default_codec  # primary models load with the first primary stream

        self.name, self.robot, self.sink = name, robot, sink
        # a driver in headless mode sends its program here, not on 50002: it tells the URCL version too
        self.programs = programs_of(session)
        self.program: ProgramSent | None = None
        self.codec = default_codec()
        families = {f.spec.type for f in self.codec.families.values()}
        codec = self.codec
        self.framing = Framing(codec.size_bytes, codec.header.size, families, codec.max_size, _tiled(codec))
        self.counts = Counts()
        self.last_time = 0.0
        self.typed: set[type] = set()  # the part classes whose column types the sink was given
        # what the Version message announced, else what the user gave (capture --controller): picks
        # older layouts
        self.given: Version | None = (session or {}).get("controller")
        self.version: Version | None = self.given
        self.reuse: Reuse = {}  # the last model of each Robot State sub-package (primary/robot_state.py)
        self.notes: list[str] = []  # why values may be wrong, once each: the summary shows them
        self.script = bytearray()  # what the client sent since the last row of primary_scripts
        self.script_time = self.script_last = 0.0  # when that began, and when its last segment came

    def feed(self, sender: str, chunk: Chunk) -> None:
        if sender == "client":  # URScript (or anything else a client sends)
            self._script(chunk)
            self._program(chunk)
            return
        self.last_time = chunk.time
        self._messages(self.framing.feed(chunk), self.framing.times, chunk.time)

    def framings(self) -> dict[str, Framing]:
        return {"controller": self.framing}

    def _script(self, chunk: Chunk) -> None:
        """What the client sends, a row per burst: the segments TCP cut one send into are one
        row (a program in 14 segments was 14 rows, a character cut in two at their edges). A row
        ends where a new `def`/`sec` begins, a gap lost bytes, or a whole line was followed by a
        pause (`SCRIPT_PAUSE`); never inside a line, unless it grows past `MAX_SCRIPT_ROW`."""
        data = chunk.data
        held = self.script
        if held and (
            chunk.gap_before
            or data.lstrip()[:4] in (b"def ", b"sec ")
            or (held.endswith(b"\n") and chunk.time - self.script_last > SCRIPT_PAUSE)
            or len(held) + len(data) > MAX_SCRIPT_ROW
        ):
            self._script_row()
        if not self.script:
            self.script_time = chunk.time
        self.script += data
        self.script_last = chunk.time

    def _script_row(self) -> None:
        if not self.script:
            return
        text, self.script = bytes(self.script), bytearray()
        row = {"connection": self.name, "capture_time": self.script_time, **text_columns("script", text)}
        self.sink.row("primary_scripts", self.robot, day_of(self.script_time), row)

    def _program(self, chunk: Chunk) -> None:
        """Keep the text a client sends as the robot's program (a new one at each `def`/`sec`)."""
        if self.programs is None:
            return
        if self.program is None or chunk.data.lstrip()[:4] in (b"def ", b"sec "):
            self.program = ProgramSent(chunk.time, bytearray())
            self.programs.add(self.robot, server_port(self.name), self.program)
        room = MAX_PROGRAM_BYTES - len(self.program.reply)
        self.program.reply += chunk.data[: max(0, room)]

    def finish(self) -> None:
        self._script_row()
        self._messages(self.framing.finish(), self.framing.times, self.last_time)

    def _messages(self, raws: list[bytes], times: list[float] | None, now: float) -> None:
        from rtde_spec.primary.codec import announced_version
        from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

        for n, raw in enumerate(raws):
            time = now if times is None else times[n]  # a message held back: when it was completed
            base = {"connection": self.name, "capture_time": time}
            day = day_of(time)
            self.counts.packages += 1
            try:
                message = self.codec.decode_message(raw, version=self.version, reuse=self.reuse)
            except RtdeSpecError as exc:
                self.counts.errors.append(f"message at {time:.6f}: {exc}")
                continue
            announced = announced_version(message)
            if announced is not None:
                if self.given is not None and announced != self.given:
                    said = f"its Version message says {announced}, --controller said {self.given}"
                    self._note(f"{said}: {announced} used")
                self.version = announced
            self._warnings(message)
            parts = message.sub_packages if isinstance(message, RobotStateMessage) else [message]
            for part in parts:
                table = f"primary_{getattr(part, 'NAME', 'unknown')}"
                if not isinstance(part, PrimaryPart):
                    self.sink.row(table, self.robot, day, {**base, **_unknown_columns(part)})
                    continue
                if type(part) not in self.typed:  # a field its version does not send is typed all the same
                    self.typed.add(type(part))
                    self.sink.hint(table, column_types(type(part)))
                self.sink.row(table, self.robot, day, {**base, **flatten_part(part)})

    def _warnings(self, message: Any) -> None:
        """Why `message`'s values may be wrong for the controller that sent it, into the notes once each."""
        from rtde_spec.primary.version_warnings import warnings_for

        for warning in warnings_for(self.codec, self.version, message):
            self._note(warning if self.version is not None else f"{warning}; {NO_VERSION}")

    def _note(self, note: str) -> None:
        if note not in self.notes and len(self.notes) < MAX_NOTES:
            self.notes.append(note)

    def close(self) -> None:
        pass


def _unknown_columns(part: Any) -> dict[str, Any]:
    """A message or sub-package of a type the spec does not know (or an opaque one): what its model
    holds, so rows of different ones can be told apart; the bytes in hex, a prefix as JSON."""
    row: dict[str, Any] = {}
    for key in type(part).model_fields:
        value = getattr(part, key)
        if isinstance(value, (bytes, bytearray)):
            row[key] = bytes(value).hex()
        elif isinstance(value, dict):
            row[key] = json.dumps(plain(value))
        else:
            row[key] = value
    return row


def _tiled(codec: Any) -> Check:
    """A candidate message of a family made of sub-packages is surely one when their sizes fill it."""
    tiled = {t for t, f in codec.families.items() if f.spec.layout == "subpackages"}
    at_type, head, sub = codec.size_bytes, codec.header.size, codec.sub_header

    def check(buf: bytearray, at: int, size: int) -> int:
        end = at + size
        if buf[at + at_type] not in tiled or end > len(buf):
            return WEAK
        pos = at + head
        while end - pos >= sub.size:
            step = sub.unpack_from(buf, pos)[0]
            if step < sub.size:
                return WEAK
            pos += step
        return STRONG if pos == end else WEAK

    return check
