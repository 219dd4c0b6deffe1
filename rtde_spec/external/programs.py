"""The programs a capture saw sent to each robot: what tells which URCL version drives it.

Light on purpose (no spec, no models): the primary interface's decoder keeps the
programs a client sends in headless mode here too, and capture imports it up front.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol


class ProgramText(Protocol):
    """A program request as the script sender's decoder keeps it: its time, the text so far."""

    time: float
    reply: bytearray


@dataclass
class Program:
    port: str  # the port it was sent on: the script sender's, or the primary interface's (headless)
    request: ProgramText


MAX_PROGRAM_BYTES = 4 << 20  # a program longer than this is not one (URCL's is 50 kB): the rest is counted


@dataclass
class ProgramSent:
    """A program a client sent the robot on its primary or secondary port (headless mode)."""

    time: float
    reply: bytearray  # the text so far (named as the script sender's reply, which it stands for)


class Programs:
    """The programs one capture saw sent to each robot, in capture order.

    One per capture file, shared by its connections: the script sender adds what it
    sees, a connection with layouts to choose from reads its robot's programs.
    """

    def __init__(self) -> None:
        self.by_robot: dict[str, list[Program]] = {}

    def add(self, robot: str, port: str, request: ProgramText) -> None:
        self.by_robot.setdefault(robot, []).append(Program(port, request))

    def around(self, robot: str, start: float) -> tuple[Program | None, Program | None]:
        """The robot's last program requested at or before `start`, and its first one after."""
        before = after = None
        for program in self.by_robot.get(robot, []):
            if program.request.time <= start:
                before = program
            elif after is None:
                after = program
        return before, after


def programs_of(session: dict[str, object] | None) -> Programs | None:
    """The programs of one capture file, shared by its connections (None: decoded alone)."""
    if session is None:
        return None
    programs = session.setdefault("urcl_programs", Programs())
    assert isinstance(programs, Programs)
    return programs
