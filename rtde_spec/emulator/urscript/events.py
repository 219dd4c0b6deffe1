"""What a running program tells the world: the messages the primary/secondary ports send for it.

The model queues these; the servers drain them and send each as the robot message a
controller sends (runtime exception, text, popup, program state, error code).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

EventKind = Literal["runtime_exception", "text", "popup", "program_started", "program_stopped", "error_code"]


@dataclass(frozen=True)
class ScriptEvent:
    """One message: `runtime_exception` carries the script line and column (1-based) it failed at."""

    kind: EventKind
    text: str
    line: int = 0
    column: int = 0
    title: str = ""
    warning: bool = False
    error: bool = False
    program: str = ""  # the program's name (its def), for program state messages
    names: tuple[str, ...] = ()  # program_started: its global variables (program_globals.py)
    code: int = 0  # an error code's number and argument (C209A0: 209, 0); `warning` its level
    argument: int = 0
