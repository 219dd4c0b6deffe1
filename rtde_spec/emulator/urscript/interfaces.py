"""The two sides a URScript call sees: the robot it drives and the program running it.

Protocols, so the interpreter's modules depend on these and not on each other.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Mapping
from typing import Any, Protocol

from rtde_spec.emulator.arm.state import Arm
from rtde_spec.emulator.urscript.events import ScriptEvent

Wait = Generator[None, None, None]


class Robot(Protocol):
    """What a program drives: the arm, the outputs, and where its messages go."""

    arm: Arm
    values: dict[str, Any]

    def apply_inputs(self, inputs: Mapping[str, Any]) -> None: ...

    def emit(self, event: ScriptEvent) -> None: ...


class Runner(Protocol):
    """A running program, as a call sees it: its robot, clock, name and the I/O calls it ran."""

    robot: Robot
    clock: float
    name: str
    applied: list[str]
    finished: bool
    current: Any  # the thread running the call (script_threads.ScriptThread)

    def wait_for(self, done: Callable[[], bool]) -> Wait: ...
