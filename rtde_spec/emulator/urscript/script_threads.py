"""What the interpreter keeps of each thread of a program, and how a thread ends."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from enum import Enum

from rtde_spec.emulator.urscript.nodes import Stmt

__all__ = ["Flow", "Killed", "LoopTurn", "ScriptThread", "close_thread"]


class Flow(Enum):
    BREAK = "break"
    CONTINUE = "continue"


@dataclass(eq=False)
class LoopTurn:
    stmt: Stmt
    epoch: int  # the control step of its latest turn


@dataclass(eq=False)
class ScriptThread:
    id: int
    name: str
    steps: Iterator[None]
    done: bool = False
    ran: int = 0  # statements since it last waited
    preempted: bool = False  # its share ran out: it goes on when time is left, not having waited
    rested: bool = False  # a read it made rested for its share's end: it may go on in this step
    caught: bool = False  # it had its share of this step already, before the arm moved (catch_up)
    loops: list[LoopTurn] = field(default_factory=list)


class Killed(Exception):
    """A thread killing itself: unwinds its own generator."""


def close_thread(thread: ScriptThread) -> None:
    thread.done = True
    close = getattr(thread.steps, "close", None)
    if close is not None:
        try:
            close()
        except (ValueError, RuntimeError):  # running or refusing to close: it is done all the same
            pass
