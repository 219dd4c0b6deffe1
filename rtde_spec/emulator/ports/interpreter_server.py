"""The interpreter socket (port 30020, e-Series 5.10 on): URScript statements, one line each, for a
program sitting in `interpreter_mode()` (urscript/interpreter_mode.py runs them).

UR's article "Interpreter mode" (SW 5.10 and above, e-Series only): "the controller opens an
interpreter socket (30020) where it accepts complete valid URScript statements". A client sends a
line ending in "\\n" and reads one reply line ending in "\\n" (UR's InterpreterHelper example reads
up to the newline and matches `(\\w+):\\W+(\\d+)?`): `ack: <id>: <statement>`, `discard: <reason>:
<statement>` or `state: <value>: <command>`. A controller whose version has no interpreter mode
has no such port (emulator/server/loop.py serves it only where the spec lists interpreter_mode()).
Each client is held to the port's limits (guard.py).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import TYPE_CHECKING

from rtde_spec.emulator.ports import INTERPRETER_PORT
from rtde_spec.emulator.ports.guard import GuardedConnection, Port, split_lines

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel
    from rtde_spec.emulator.urscript.interpreter_mode import InterpreterState

__all__ = ["INTERPRETER_PORT", "InterpreterConnection", "InterpreterHub", "has_interpreter_mode"]
log = logging.getLogger("rtde_spec.emulator")


def has_interpreter_mode(model: ControllerModel) -> bool:
    """Whether the model's controller version has interpreter mode (spec/urscript: e-Series 5.10 on)."""
    from rtde_spec.emulator.urscript import builtins

    line = model.line
    return "interpreter_mode" in builtins.names_for(line.id, str(model.version), line.inherits)


class InterpreterHub:
    """What the interpreter connections share: the model, and the interpreter of the program
    that ran last (its ids answer the state commands while no program runs)."""

    def __init__(self, model: ControllerModel) -> None:
        self.model = model
        self.last: InterpreterState | None = None

    def answer(self, lines: list[str], reply: Callable[[str], None]) -> None:
        """Lines one read brought: each received, then what time allows interpreted at once."""
        from rtde_spec.emulator.urscript.interpreter_mode import interpret, receive, state_of

        program = self.model.program
        for line in lines:
            receive(program, line, reply, self.last)
        if program is not None and not program.finished:
            self.last = state_of(program)
            interpret(program, self.last)


class InterpreterConnection(GuardedConnection):
    """One interpreter-socket client: a reply line per line it sends (some when interpreted)."""

    def __init__(self, hub: InterpreterHub, port: Port) -> None:
        super().__init__(port)
        self.hub = hub
        self.buffer = bytearray()

    def data_received(self, data: bytes) -> None:
        if self.dropped:
            return
        self.buffer, lines = split_lines(self.buffer, data)
        if not self.received(len(self.buffer), len(lines)):
            return
        texts = [text for text in (raw.decode("utf-8", "replace").strip() for raw in lines) if text]
        if texts:
            log.debug("interpreter %s: %d lines, the first %r", self.peer, len(texts), texts[0][:80])
            self.hub.answer(texts, self.reply)

    def reply(self, text: str) -> None:
        if text.startswith("discard"):  # what a client's author looks for in the log
            log.info("interpreter %s: %s", self.peer, text[:200])
        self.write(text.encode("utf-8", "replace") + b"\n")
