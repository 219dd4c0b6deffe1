"""The emulator's primary and secondary ports: the Version message, then Robot State at 10 Hz
with every sub-package the controller version sends (state_message.py), and on the
primary ports the robot messages of what happened (robot_messages.py).

The Robot State is built from the same model the RTDE port reads, so a client sees
the same joint positions and modes on both. What a client sends is cut into
scripts (a line, or a `def ... end` program; script_framer.py), the last few kept, the
plain commands drivers send (`power on`, `stop program`; primary_commands.py) done,
the rest run as URScript (`script.py`); read-only ports drop what they get, as a controller does.
Each client is held to the port's limits (guard.py).
"""

from __future__ import annotations

import logging
from collections import deque
from typing import TYPE_CHECKING

from rtde_spec._generated.enums import RobotMode
from rtde_spec.emulator.controller.model import BACKGROUND_PARSE
from rtde_spec.emulator.ports.guard import Port
from rtde_spec.emulator.ports.primary_commands import take_commands
from rtde_spec.emulator.ports.robot_messages import (
    event_messages,
    global_variables_update,
    prepare,
    program_threads_message,
    safety_mode_message,
    version_message,
)
from rtde_spec.emulator.ports.script import run_script
from rtde_spec.emulator.ports.script_framer import ScriptPort
from rtde_spec.emulator.ports.state_message import RobotStateBuilder, available
from rtde_spec.emulator.urscript.program_globals import global_names
from rtde_spec.printable import safe_text

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel

log = logging.getLogger("rtde_spec.emulator")

# The Global Variables Update's values are typed as the 5.9/5.10 and the current primary documents
# give them (the spec's value_types); UnderAutomation's Universal Robots SDK documents another way
# to decode them from 3.2 to 5.8, which no public document gives: those versions get the setup
# message's names and no values rather than values typed as they are not.
VALUES_SINCE = {"e-series": "5.9.0"}
KEEP_SCRIPTS = 64  # the last scripts received, for tests and `watch` to look at


class PrimaryHub:
    """Connections of the primary/secondary ports, the scripts they received, what they are sent."""

    def __init__(self, model: ControllerModel) -> None:
        self.model = model
        self.connections: set[PrimaryConnection] = set()
        self.scripts: deque[tuple[int, str]] = deque(maxlen=KEEP_SCRIPTS)  # (port, script text)
        self.state = RobotStateBuilder(model)
        self.states = 0
        self._safety_mode = self._robot_mode = -1
        self._labels: list[tuple[str, int, str]] = []  # the threads' labels last sent (Program Threads)
        self._values = available(VALUES_SINCE, model.version, model.catalogue)
        self._globals_of: object = None  # the program whose global variable names these are
        self._global_names: tuple[str, ...] = ()
        self._global_next = 0  # where the next update starts (a program's values take several when big)
        prepare()  # the messages' codec now, not in the control step of a program's start

    def run(self, port: int, text: str) -> None:
        """A whole script from a client: kept (the last few), its plain commands (`power on`, ...;
        primary_commands.py) done, the URScript left run on the model."""
        self.scripts.append((port, text))
        text = take_commands(self.model, text)
        if not text:
            return
        applied = run_script(self.model, text)
        if len(text) > BACKGROUND_PARSE:  # read off the control loop: it starts (or is refused) later
            log.info(
                "URScript on port %d: %s (%d characters, read off the control loop)",
                port,
                safe_text(text.strip()[:80]),
                len(text),
            )
        else:
            log.info(
                "URScript on port %d: %s (%d I/O calls run)", port, safe_text(text.strip()[:80]), len(applied)
            )

    def version_message(self) -> bytes:
        return version_message(self.model.version, self._micros())

    def robot_state(self, first: bool = False) -> bytes:
        """One Robot State message as a client gets it (`first`: the one after connecting)."""
        return self.state.build(first=first)

    def broadcast_state(self) -> None:
        """Every 100 ms: robot messages since the last time (primary ports), then Robot State."""
        values = self.model.values
        drain = getattr(self.model, "drain_events", None)
        events = drain() if drain is not None else ()
        safety, mode = int(values.get("safety_mode", 0)), int(values.get("robot_mode", 0))
        safety_changed = safety != self._safety_mode and self._safety_mode != -1
        # leaving initialisation (powered on from off): Kinematics Info goes out again
        kinematics = self._robot_mode != -1 and self._robot_mode < RobotMode.IDLE <= mode
        self._safety_mode, self._robot_mode = safety, mode
        self.states += 1
        if not self.connections:
            return  # the events are gone (a controller keeps none for later clients): none encoded
        burst = b""
        if any(conn.messages for conn in self.connections):
            micros = self._micros()
            messages = [m for event in events for m in event_messages(event, micros)]
            if safety_changed:
                messages.append(safety_mode_message(safety, micros))
            update = self._global_variables(micros)
            if update:
                messages.append(update)
            labels = self._program_labels()
            if labels and labels != self._labels:
                messages.append(program_threads_message(labels, micros))
            self._labels = labels
            burst = b"".join(messages)
        periodic = first = b""
        for conn in list(self.connections):
            if conn.fresh:
                first = first or self.state.build(first=True)
                data = first
                conn.fresh = False
            else:
                periodic = periodic or self.state.build(
                    kinematics=kinematics, per_second=self.states % 10 == 0
                )
                data = periodic
            conn.send(burst + data if conn.messages else data)

    def _global_variables(self, micros: int) -> bytes:
        """The running program's Global Variables Update ("sent every 100ms" after the setup message
        its start sent, UR's primary interface document): its globals' values, in the setup's order."""
        program = getattr(self.model, "program", None)
        script = getattr(program, "script", None)
        if script is None or not self._values:
            return b""
        if program is not self._globals_of:
            self._globals_of, self._global_names, self._global_next = program, global_names(script), 0
        if not self._global_names:
            return b""
        values = program.globals  # type: ignore[union-attr]
        update, self._global_next = global_variables_update(
            [values.get(name) for name in self._global_names], micros, self._global_next
        )
        return update

    def _program_labels(self) -> list[tuple[str, int, str]]:
        """(thread, label number, label text) of the running program's threads that passed a label
        (PolyScope writes `$ N "text"` before each program node): what the Program Threads message
        reports; sent when it changed since the last broadcast, at most every 100 ms."""
        program = getattr(self.model, "program", None)
        labels = getattr(program, "thread_labels", None)
        return labels() if labels is not None else []

    def _micros(self) -> int:
        return int(self.model.time * 1_000_000)


class PrimaryConnection(ScriptPort):
    """One client of a primary/secondary port: the Version message, Robot State, its scripts run."""

    def __init__(self, hub: PrimaryHub, port: Port, number: int, read_only: bool, messages: bool) -> None:
        super().__init__(port)
        self.hub, self.number, self.read_only = hub, number, read_only
        self.messages = messages  # robot messages go to the primary ports only, not the secondary
        self.fresh = True  # its first Robot State carries the once-per-connection sub-packages

    def opened(self) -> None:
        self.hub.connections.add(self)
        self.write(self.hub.version_message())

    def closed(self) -> None:
        self.hub.connections.discard(self)

    def run_script(self, text: str) -> None:
        self.hub.run(self.number, text)

    def send(self, data: bytes) -> None:
        self.write(data)
