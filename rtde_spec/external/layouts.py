"""Which layout of a URCL message a session sends, and why: capture's choice for a message
with `older` layouts in the spec (the reverse command, the trajectory point, the script
command).

The program the driver sent to the robot (the script sender's reply) says it best: each
layout's `detect` lines (spec/external_control/protocols.yaml) are lines of the program,
the multipliers the driver writes into it included, and its `without` lines must not be
in it (a later version kept the older lines and added one). Without that program (a
capture started late, a program no layout's lines name) the records themselves rule layouts
out, and only where the wire leaves no doubt: URCL writes each record with one write of
the whole record, so the TCP segments of a layout hold whole records of its size; and a
record of a layout carries only the enum values that layout has. What no segment and no
record rules out stays: one layout left is taken, else the newest of them (the spec's
order, newest first), and the reason says it was assumed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from rtde_spec.external.codec import record_codec
from rtde_spec.external.programs import Programs
from rtde_spec.metamodel.external import RecordMessage, program_line


@dataclass(frozen=True)
class Choice:
    layout: str | None  # the codec's `layout` argument: None for the newest
    name: str
    why: str


def named_by(message: RecordMessage, text: bytes) -> list[str]:
    """Names of the layouts whose detect lines the program has and whose `without` lines it has
    not, unless it sets a multiplier they do not name (scales the spec does not know)."""
    lines = frozenset(program_line(line) for line in text.decode("utf-8", "replace").splitlines())
    return [name for _, name, detect, _ in message.layouts() if detect is not None and detect.matches(lines)]


def fitting(protocol: str, message: RecordMessage, segments: Sequence[bytes]) -> list[str]:
    """Names of the layouts (newest first) every segment is whole records of, each record
    holding only enum values its layout knows."""
    data = [s for s in segments if s]
    out: list[str] = []
    for layout, name, _, size in message.layouts():
        if not data or any(len(s) % size for s in data):
            continue
        codec = record_codec(protocol, message.name, layout)
        if all(codec.plausible(s, at) for s in data for at in range(0, len(s), size)):
            out.append(name)
    return out


class LayoutChooser:
    """The layout of one connection's `message` records: from its robot's program, else its records."""

    def __init__(self, protocol: str, message: RecordMessage, robot: str, programs: Programs | None) -> None:
        self.protocol, self.message, self.robot = protocol, message, robot
        self.programs = programs or Programs()
        self.args = {name: layout for layout, name, _, _ in message.layouts()}

    def choose(self, start: float, segments: Sequence[bytes], final: bool) -> Choice | None:
        """The choice for a connection that began at `start`; None: wait for more (never when `final`).

        Before the end only the program requested before the connection can decide (it is
        normally whole by then); at the end a later program of the same robot may (the
        capture began after the session's request), then the records.
        """
        before, after = self.programs.around(self.robot, start)
        seen = before if before is not None or not final else after
        named: list[str] = []
        if seen is not None:
            named = named_by(self.message, bytes(seen.request.reply))
            if len(named) == 1:
                which = "the script" if seen is before else "a later script"
                return self._choice(named[0], f"from {which} on {seen.port}")
        if not final:
            return None
        if seen is None:
            about = "no script seen"
        elif named:
            about = f"the script on {seen.port} names several: {', '.join(named)}"
        else:
            about = f"the script on {seen.port} names none"
        fits = fitting(self.protocol, self.message, segments)
        if len(fits) == 1:
            return self._choice(fits[0], f"from the records: no other layout fits them; {about}")
        if fits:
            return self._choice(
                fits[0], f"assumed: newest of the layouts the records fit, {', '.join(fits)}; {about}"
            )
        newest = self.message.layouts()[0][1]
        return self._choice(newest, f"assumed: newest; the records fit no layout; {about}")

    def _choice(self, name: str, why: str) -> Choice:
        return Choice(self.args[name], name, why)
