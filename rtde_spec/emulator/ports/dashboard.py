"""The emulator's dashboard server (port 29999): text commands that drive the same controller model.

Commands and reply texts come from spec/dashboard/commands.yaml (through the generated
table): a greeting line on connect, then one reply line per command line. `power on`,
`brake release`, `power off`, `load`/`play`/`pause`/`stop` and `unlock protective stop`
act through the model's mode methods, so what they do shows on RTDE and the primary
ports too. `load NAME` reads a URScript program from the programs directory: NAME
itself when it is a script, the `.script` PolyScope saves beside a `.urp`, or else the
`.urp`'s program tree, translated (`emulator/controller/urp.py`); a path into the
controller's own folder (/programs, URSim's /ursim/programs) names the file in it. A
program that runs stops first, so `programState` answers `STOPPED NAME` (what UR's client
library waits for).
A command the controller version does not have gets the `unknown` reply, as a
controller answers it. Each client is held to the port's limits (guard.py).
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.enums import ProgramState, RobotMode, SafetyMode, SafetyStatus, SafetyStatusBits
from rtde_spec.emulator.ports.guard import GuardedConnection, Port, split_lines
from rtde_spec.emulator.ports.robot_messages import BUILD_DATE
from rtde_spec.emulator.ports.state_message import arm_parameters, available, robot_type
from rtde_spec.metamodel.dashboard import DashboardCommand, dashboard_spec

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel

log = logging.getLogger("rtde_spec.emulator")
SERIAL_NUMBER = "20245500001"  # UR serial numbers start with the year of make
MAX_PROGRAM_BYTES = 1 << 20
NO_PROGRAM = "<unnamed>"
USER_ROLES = ("PROGRAMMER", "OPERATOR", "NONE", "LOCKED", "RESTRICTED")
# where a robot and URSim keep their programs: a path into them names the file in ours
CONTROLLER_PROGRAMS = (Path("/programs"), Path("/ursim/programs"))


class DashboardHub:
    """What the dashboard connections share: the model, the loaded program's name, the stop clock."""

    def __init__(
        self,
        model: ControllerModel,
        programs: Path | None = None,
        serial_number: str = SERIAL_NUMBER,
        external_control: str | None = None,
    ) -> None:
        self.model = model
        self.table = dashboard_spec()
        self.programs = programs
        self.serial_number = serial_number
        self.program: str | None = None  # file name of the loaded program
        self.installation = "default.installation"
        self.user_role = "PROGRAMMER"  # CB3's setUserRole
        self.operational_mode = "NONE"  # e-Series: no client controls it until `set operational mode`
        self.reports = 0
        self.available = model.line.id in self.table.product_lines
        self.external_control = external_control  # HOST[:PORT] of the driver (None: the one who plays)
        self.waiting_for_driver: str | None = None  # a loaded .urp whose External Control node needs it
        self.peer = "127.0.0.1"  # the client of the command being answered

    def answer(self, line: str, peer: str = "127.0.0.1") -> tuple[str, bool]:
        """The reply to one command line (from the client at `peer`), and whether the connection
        closes after it."""
        self.peer = peer
        found = self.table.find(line)
        if found is None or not available(found[0].since, self.model.version, self.model.catalogue):
            return self.table.unknown.format(line=line), False
        command, argument = found
        if command.quoted and len(argument) >= 2 and argument[0] == argument[-1] == '"':
            argument = argument[1:-1]
        try:
            outcome = self._act(command, argument)
        except Exception as exc:  # whatever a command meets is its failure reply, never a closed socket
            log.warning("dashboard %r failed: %s", line[:80], exc)
            outcome = "failed"
        text = command.replies.get(outcome, command.replies["ok"])  # type: ignore[call-overload]
        values = self.values()
        if command.argument:
            values[command.argument] = argument
        return text.format(**values), command.action == "quit"

    # --- what the commands do -----------------------------------------------

    def _act(self, command: DashboardCommand, argument: str) -> str:
        model: Any = self.model  # the mode methods of ControllerModel (emulator/controller/modes.py)
        action = command.action
        if action == "load":
            return self._load(argument)
        if action == "load_installation":
            found = self._find(argument)
            if isinstance(found, Path):
                self.installation = found.name
                return "ok"
            return found
        if action == "set_user_role":
            if argument.upper() not in USER_ROLES:
                return "failed"
            self.user_role = argument.upper()
        elif action == "set_operational_mode":
            if argument.upper() not in ("MANUAL", "AUTOMATIC"):
                return "failed"
            self.operational_mode = argument.upper()
        elif action == "clear_operational_mode":
            self.operational_mode = "NONE"
        elif action == "loaded_program":
            return "ok" if self.program else "failed"
        elif action == "log":
            log.info("dashboard log: %s", argument)
        elif action == "power_on":
            model.power_on()
        elif action in ("power_off", "shutdown"):
            model.power_off()
        elif action == "brake_release":  # from power off too: powered on, then released (URSim does)
            model.power_on()
            model.release_brakes()
        elif action == "play":
            if self.waiting_for_driver is not None and model.program is None:
                return self._play_external(self.waiting_for_driver)
            return "ok" if model.play() else "failed"
        elif action == "pause":
            return "ok" if model.pause_program() else "failed"
        elif action == "stop":
            model.stop_program()
        elif action == "unlock_protective_stop":
            if model.unlock_wait() > 0:  # the model's clock: from the stop itself (modes.UNLOCK_AFTER)
                return "failed"
            model.unlock_protective_stop()
        elif action == "restart_safety":
            model.power_off()
            self._safety_normal()
        return "ok"

    def _find(self, name: str, suffix: str | None = None) -> Path | str:
        """The file `name` is in the programs directory, else the outcome ("not_found").

        The name is transformed first (.urp to `suffix`), then resolved (symlinks followed),
        then checked to be inside the folder: one check on the path that is opened.
        A name the file system refuses (a NUL byte, too long) is a file not found.
        """
        if self.programs is None or not name or "\0" in name:
            return "not_found"
        try:
            base = self.programs.resolve(strict=True)
            wanted = _in_programs(name)
            if suffix is not None and wanted.suffix == ".urp":
                wanted = wanted.with_suffix(suffix)
            path = (base / wanted).resolve(strict=True)  # every link followed, to the file itself
            if not path.is_relative_to(base) or not path.is_file():
                return "not_found"
        except (OSError, ValueError, RuntimeError):  # missing, a loop of links, a name too long
            return "not_found"
        return path

    def _load(self, name: str) -> str:
        """Load `name` from the programs directory: a script, the .script saved beside a .urp, or
        else the .urp itself, translated as PolyScope would run it (`emulator/controller/urp.py`)."""
        path = self._find(name, ".script")
        if not isinstance(path, Path):
            return self._load_urp(name) if self._without_script(name) else path
        try:
            if path.stat().st_size > MAX_PROGRAM_BYTES:
                return "failed"
            text = path.read_text(encoding="utf-8")
        except OSError:
            return "not_found"
        except UnicodeDecodeError:
            return "failed"
        return self._loaded(name, text)

    def _without_script(self, name: str) -> bool:
        """A .urp with no .script beside it at all: one that is there but refused (a link out of
        the folder) stays refused, the .urp is not run in its place."""
        if self.programs is None or Path(name).suffix != ".urp" or "\0" in name:
            return False
        try:
            return not os.path.lexists(self.programs / _in_programs(name).with_suffix(".script"))
        except (OSError, ValueError):
            return False

    def _load_urp(self, name: str) -> str:
        from rtde_spec.emulator.controller.urp import UrpError, urp_to_script

        path = self._find(name)
        if not isinstance(path, Path):
            return path
        try:
            if path.stat().st_size > MAX_PROGRAM_BYTES:
                return "failed"
            text = urp_to_script(path.read_bytes(), Path(name).stem)
        except OSError:
            return "not_found"
        except UrpError as exc:  # the dashboard only says it failed: the log says why
            log.warning("load %s: %s", name, exc)
            return "failed"
        return self._loaded(name, text)

    def _loaded(self, name: str, text: str) -> str:
        from rtde_spec.emulator.controller.external_program import NODE_MARK

        model: Any = self.model
        if model.program is not None:  # the running program stops: what is loaded is then STOPPED
            model.stop_program()
        model.load_program(text)
        self.program = Path(name).name
        self.waiting_for_driver = text if NODE_MARK in text else None
        return "ok"

    def _play_external(self, script: str) -> str:
        """Play a program with the External Control node: its program is asked of the driver off
        the control loop, as PolyScope asks for it, and the program starts once it is there."""
        from rtde_spec.emulator.controller import external_program

        model: Any = self.model
        if not model.can_move():
            return "failed"
        host, port = external_program.address(self.external_control, self.peer)
        model.run_script_later(lambda: external_program.insert(script, external_program.fetch(host, port)))
        return "ok"

    def _safety_normal(self) -> None:
        values = self.model.values
        for name, value in (
            ("safety_mode", SafetyMode.NORMAL),
            ("safety_status", SafetyStatus.NORMAL),
            ("safety_status_bits", SafetyStatusBits.NORMAL_MODE),
        ):
            if name in values:
                values[name] = int(value)

    # --- what the replies say -------------------------------------------------

    def values(self) -> dict[str, str]:
        values, version = self.model.values, self.model.version
        mode = int(values.get("robot_mode", RobotMode.RUNNING))
        safety = int(values.get("safety_mode", SafetyMode.NORMAL))
        status = int(values.get("safety_status", safety))
        runtime = int(values.get("runtime_state", ProgramState.STOPPED))
        state = {
            ProgramState.RUNNING: "PLAYING",
            ProgramState.PAUSED: "PAUSED",
            ProgramState.PAUSING: "PAUSED",
        }
        kind, _ = robot_type(arm_parameters(self.model))
        running = "true" if runtime == ProgramState.RUNNING else "false"  # lower case on CB3 too
        return {
            "robot_mode": _name(RobotMode, mode),
            "safety_mode": _name(SafetyMode, safety),
            "safety_status": _name(SafetyStatus, status),
            "program_state": state.get(runtime, "STOPPED"),  # type: ignore[call-overload]
            "program": self.program or NO_PROGRAM,
            "running": running,
            "saved": "true",
            "installation": self.installation,
            "user_role": self.user_role,
            "operational_mode": self.operational_mode,
            "report_id": str(self.reports),
            "support_file": f"ur_{self.serial_number}_support_file.zip",
            "version": f"{version.major}.{version.minor}.{version.bugfix}.{version.build or 0}",
            "build_date": BUILD_DATE,
            "serial_number": self.serial_number,
            "robot_model": _robot_model(kind),
        }


def _in_programs(name: str) -> Path:
    """`name` relative to the programs directory: `/programs/x.urp` (a robot's folder, as URCL's
    tests load from URSim's /ursim/programs) is `x.urp`; other names are left as they are."""
    wanted = Path(name)
    for folder in CONTROLLER_PROGRAMS:
        if wanted.is_relative_to(folder):
            return wanted.relative_to(folder)
    return wanted


def _name(enum: Any, value: int) -> str:
    try:
        return str(enum(value).name)
    except ValueError:
        return str(value)


def _robot_model(kind: int) -> str:
    from rtde_spec._generated.enums import RobotType

    return _name(RobotType, kind)


class DashboardConnection(GuardedConnection):
    """One dashboard client: the greeting, then a reply line per command line."""

    def __init__(self, hub: DashboardHub, port: Port) -> None:
        super().__init__(port)
        self.hub = hub
        self.buffer = bytearray()

    def opened(self) -> None:
        self.write(self.hub.table.greeting.encode() + b"\n")

    def data_received(self, data: bytes) -> None:
        if self.dropped:
            return
        self.buffer, lines = split_lines(self.buffer, data)
        if len(self.buffer) > self.hub.table.max_line_bytes:
            self.drop(f"a line of over {self.hub.table.max_line_bytes} bytes is no dashboard command")
            return
        if not self.received(len(self.buffer), len(lines)):
            return
        for raw in lines:
            line = raw.decode("utf-8", "replace").strip()
            if not line:
                continue
            peername = self.transport.get_extra_info("peername") if self.transport is not None else None
            reply, close = self.hub.answer(line, _host(peername))
            log.info("dashboard %s: %r -> %r", self.peer, line[:80], reply)
            self.write(reply.encode("utf-8", "replace") + b"\n")
            if close:
                assert self.transport is not None
                self.transport.close()
                return


def _host(peername: object) -> str:
    """The address of a connection's peer (transport's peername: (host, port, ...))."""
    return str(peername[0]) if isinstance(peername, tuple) and peername else "127.0.0.1"
