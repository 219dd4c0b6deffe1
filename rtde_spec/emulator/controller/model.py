"""The emulated controller's state: every output the version has, moved by time, inputs and programs.

Defaults describe a powered robot in RUNNING mode with no program; the timestamp
advances with the control steps; URScript programs move the arm (`program.py`),
and joints, TCP pose and speed, runtime state and speed scaling follow each step;
a scenario sets outputs as constants or functions of time (and the TCP pose then
follows the scenario's joints); inputs change the outputs a real controller reflects
them in (digital and analog outputs, the speed slider, every input register's
read-back). The dashboard's power, brake, stop and play requests act through the
methods of `RobotModes`. Enum values and bit positions come from the generated tables.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable, Mapping
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

from rtde_spec._generated.enums import (
    AnalogIoTypes,
    DigitalIoBits,
    JointMode,
    ProgramState,
    RobotMode,
    RobotStatusBits,
    SafetyMode,
    SafetyStatus,
    SafetyStatusBits,
    StandardAnalogOutputBits,
)
from rtde_spec.emulator.arm.motion import MotionError
from rtde_spec.emulator.arm.state import Arm
from rtde_spec.emulator.controller import runstate
from rtde_spec.emulator.controller.modes import RobotModes
from rtde_spec.emulator.controller.program import PROGRAM_ERRORS, Program, runtime_text
from rtde_spec.emulator.urscript import ScriptFault, parse_program
from rtde_spec.emulator.urscript.events import ScriptEvent
from rtde_spec.emulator.urscript.program_globals import global_names
from rtde_spec.metamodel.arms import arm_model
from rtde_spec.metamodel.catalogue import Catalogue, FieldInfo
from rtde_spec.metamodel.versions import Version
from rtde_spec.printable import safe_text

HOME_Q = (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)
DEFAULTS: dict[str, Any] = {
    "robot_mode": int(RobotMode.RUNNING),
    "safety_mode": int(SafetyMode.NORMAL),
    "safety_status": int(SafetyStatus.NORMAL),
    "runtime_state": int(ProgramState.STOPPED),
    "joint_mode": (int(JointMode.RUNNING),) * 6,
    "robot_status_bits": int(RobotStatusBits.POWER_ON),
    "safety_status_bits": int(SafetyStatusBits.NORMAL_MODE),
    "speed_scaling": 1.0,
    "target_speed_fraction": 1.0,
    "actual_q": HOME_Q,
    "target_q": HOME_Q,
    "joint_temperatures": (30.0,) * 6,
    "actual_main_voltage": 48.0,
    "actual_robot_voltage": 48.0,
}
# where each group of digital outputs starts in actual_digital_output_bits
_SHIFT = {
    "standard": DigitalIoBits.STANDARD_0.bit_length() - 1,
    "configurable": DigitalIoBits.CONFIGURABLE_0.bit_length() - 1,
    "tool": DigitalIoBits.TOOL_0.bit_length() - 1,
}
_ANALOG_OUT_VOLTAGE = (AnalogIoTypes.ANALOG_OUTPUT_0_VOLTAGE, AnalogIoTypes.ANALOG_OUTPUT_1_VOLTAGE)
_ANALOG_OUT_SELECT = (
    StandardAnalogOutputBits.STANDARD_ANALOG_OUTPUT_0,
    StandardAnalogOutputBits.STANDARD_ANALOG_OUTPUT_1,
)


def _zero(info: FieldInfo) -> Any:
    one: Any = {"float": 0.0, "int": 0, "bool": False}[info.wire.kind]
    return one if info.wire.count == 1 else (one,) * info.wire.count


# the robot's own state, held whatever outputs the version's RTDE has (CB3 before 3.3 has no RTDE,
# yet its primary and real-time ports show joints, pose and modes)
STATE = (
    "robot_mode", "safety_mode", "runtime_state", "joint_mode", "speed_scaling", "target_speed_fraction",
    "actual_q", "target_q", "actual_qd", "target_qd", "target_qdd",
    "actual_TCP_pose", "target_TCP_pose", "actual_TCP_speed", "target_TCP_speed",
)  # fmt: skip
MAX_EVENTS = 1000  # messages kept for the servers to send; the oldest go first
NOT_READY = "The robot is not ready: power it on, release the brakes and clear any safety stop"
log = logging.getLogger("rtde_spec.emulator")
BACKGROUND_PARSE = 16 << 10  # characters: a longer program is read in a worker thread, so the
# control loop never waits for the parser (a 64,000-line call takes about half a second to read)
MAX_PARSING = 4  # programs being read at once; more are refused
_PARSER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="urscript-parser")
SECONDARY_STEPS = 10_000  # a `sec` program runs at once; this bounds it
# the Tool Communication Interface as a controller starts (off, PolyScope's default settings);
# set_tool_communication changes it, the primary Tool Communication Info shows it
TOOL_COMMUNICATION = {
    "tool_communication_is_enabled": False, "baud_rate": 115200, "parity": 0, "stop_bits": 1,
    "rx_idle_chars": 1.5, "tx_idle_chars": 3.5,
}  # fmt: skip


class ControllerModel(RobotModes):
    """Output values by name, for one controller version and one arm model (default UR5e)."""

    def __init__(
        self,
        version: str,
        catalogue: Catalogue | None = None,
        functions: Mapping[str, Callable[[float], Any]] | None = None,
        model: str = "UR5e",
    ) -> None:
        self.catalogue = catalogue or Catalogue.default()
        self.version = Version.parse(version)
        self.line = self.catalogue.line_of(self.version)
        self.base_hz = self.line.rtde_max_frequency
        self.outputs = {i.name: i for i in self.catalogue.fields("output", self.version)}
        self.inputs = {i.name: i for i in self.catalogue.fields("input", self.version)}
        self.values: dict[str, Any] = {n: DEFAULTS.get(n, _zero(i)) for n, i in self.outputs.items()}
        for name in STATE:
            self.values.setdefault(name, DEFAULTS.get(name, (0.0,) * 6))
        self.functions = dict(functions or {})
        self.arm = Arm(arm_model(model), HOME_Q)
        self.program: Program | None = None
        self.paused = False
        self.loaded: str | None = None  # a program the dashboard loaded, run by play()
        self.calibrated = True  # the arm's kinematics calibration (a scenario may say it has none)
        self.events: deque[ScriptEvent] = deque(maxlen=MAX_EVENTS)
        self.inputs_seen: dict[str, float] = {}  # RTDE input name -> model time it was last written
        self.tool_communication: dict[str, Any] = dict(TOOL_COMMUNICATION)
        # (output group, pin) -> runstate choice (set_runstate_*_output_to_value): the controller keeps
        # them beyond the program, and sets the outputs when a program starts and ends (runstate.py)
        self.runstate_outputs: dict[tuple[str, int], int] = {}
        self._parsing: deque[Future[Program | ScriptEvent]] = deque()  # programs read off the loop
        self._published: tuple[Any, ...] = ()
        self._limits_checked = -1  # the arm revision whose joints were last checked against the limits
        self.step = 0
        self.time = 0.0
        self.tick(0)

    def tick(self, step: int) -> None:
        """Move to control step `step`: the arm and its program, the timestamp, scenario functions."""
        dt = max(0, step - self.step) / self.base_hz
        self.step = step
        if self._parsing:
            self._start_parsed()
        self.time = step / self.base_hz
        values = self.values
        # After a stall (the server skipped steps, 100 ms late) the arm and its program take one
        # control step and stand still for the rest, as the steps a real controller never skips: a
        # held speed lasts the one step a program asked for (a driver's speedj spline, URCL's), and
        # a program's socket time-out does not run out while the server, not its driver, was late.
        if dt > 0 and self.can_move() and not self.paused:
            self._advance(min(dt, 1.0 / self.base_hz))
        if "timestamp" in values:
            values["timestamp"] = self.time
        self._publish()
        for name, fn in self.functions.items():
            values[name] = fn(self.time)
        if "actual_q" in self.functions and "actual_TCP_pose" not in self.functions:
            values["actual_TCP_pose"] = self.arm.pose(values["actual_q"])  # consistent with the joints

    def _advance(self, dt: float) -> None:
        """One control step of motion (slowed by the speed slider) and of the program."""
        slider = float(self.values.get("target_speed_fraction", 1.0))
        before = [float(v) for v in self.arm.state.q]
        # a thread cut off at the last step's end commands this step's motion before the arm moves
        budget = self.program.catch_up() if self.program is not None else None
        try:
            self.arm.step(dt * slider)
            if not all(math.isfinite(float(v)) for v in self.arm.state.q):
                raise ValueError("the motion gave a joint position that is not a number")
        except (MotionError, ArithmeticError, ValueError) as exc:
            line = self.arm.motion.line if self.arm.motion is not None else 0
            self.arm.halt()
            if not all(math.isfinite(float(v)) for v in self.arm.state.q):
                self.arm.place(before)  # the arm stays where it was: never NaN for good
            if isinstance(exc, MotionError) and self.program is not None:  # out of reach on the way
                return self.stopped_on_the_way(str(exc))  # the program stays paused at its move
            if self.program is not None:
                self.program.fail(ScriptFault(str(exc), line, 1))
        if self.arm.motion is not None or self.arm.revision != self._limits_checked:
            self._limits_checked = self.arm.revision
            over = self.arm.over_limit()
            if over is not None:
                self.joint_limit_hit(over)
                return
        program = self.program
        if program is not None:
            program.advance(dt, budget)
            if program.finished:
                self._end_program()

    def joint_limit_hit(self, joint: int) -> None:
        """A joint at its position limit: it stops there, a protective stop, a runtime exception.

        The motion is dropped (the program, paused, goes on past it when played again);
        the safety mode reaches every port, the message the primary ports.
        """
        low, high = self.arm.model.joint_limits[joint]
        q = [float(v) for v in self.arm.state.q]
        limit = high if q[joint] > high else low if q[joint] < low else q[joint]
        q[joint] = limit
        motion = self.arm.motion
        line = motion.line if motion is not None else 0
        self.arm.place(q)
        program = self.program.name if self.program is not None else ""
        text = f"Joint {joint} position limit violated ({limit:.4f} rad): protective stop"
        self.emit(ScriptEvent("runtime_exception", text, line, 1 if line else 0, program=program))
        self.protective_stop()

    def _publish(self) -> None:
        """Joints, TCP pose and speed, runtime state and speed scaling into the outputs."""
        values, state = self.values, self.arm.state
        frozen = self.paused or not self.can_move()
        slider = float(values.get("target_speed_fraction", 1.0))
        key = (self.arm.revision, frozen, slider, self.arm.tcp)
        if key == self._published:
            return  # an arm at rest: its outputs are already there
        self._published = key
        q = tuple(float(v) for v in state.q)
        qd = (0.0,) * 6 if frozen else tuple(float(v) for v in state.qd)
        qdd = (0.0,) * 6 if frozen else tuple(float(v) for v in state.qdd)
        pose = self.arm.pose()
        speed = (0.0,) * 6 if frozen else self.arm.tcp_speed()
        for name, value in (
            ("actual_q", q), ("target_q", q), ("actual_qd", qd), ("target_qd", qd), ("target_qdd", qdd),
            ("actual_TCP_pose", pose), ("target_TCP_pose", pose),
            ("actual_TCP_speed", speed), ("target_TCP_speed", speed), ("tcp_offset", self.arm.tcp),
        ):  # fmt: skip
            if name in values:
                values[name] = value
        if "speed_scaling" in values:
            values["speed_scaling"] = 0.0 if frozen else slider

    # --- programs -------------------------------------------------------------

    def run_script(self, text: str) -> Program | None:
        """Start `text` as the robot's program (a `sec` program runs beside it, at once).

        A script that cannot be read, names something unknown, or comes while the
        arm cannot move is refused with a runtime exception event; nothing of it runs.
        """
        if len(text) > BACKGROUND_PARSE:  # read off the control loop, started by a later tick
            if len(self._parsing) >= MAX_PARSING:
                self.emit(ScriptEvent("runtime_exception", "too many programs at once: refused", 0, 0))
                return None
            self._parsing.append(_PARSER.submit(self._compile, text))
            return None
        return self._start(self._compile(text))

    def start_loaded(self) -> bool:
        """Start the loaded program: True once it runs, or while a long one is read off the control
        loop (PolyScope's generated programs, 40-100 kB with their URCaps' preambles, are): play
        is accepted then, and a program that does not compile says so as a runtime exception."""
        if self.loaded is None:
            return False
        reading = len(self._parsing)
        return self.run_script(self.loaded) is not None or len(self._parsing) > reading

    def run_script_later(self, make: Callable[[], str]) -> None:
        """Start the program `make` returns once it has it, off the control loop (a program the
        External Control node asks of the driver); its error (OSError) is a runtime exception."""

        def compiled() -> Program | ScriptEvent:
            try:
                return self._compile(make())
            except OSError as exc:
                return ScriptEvent("runtime_exception", str(exc), 0, 0)

        if len(self._parsing) >= MAX_PARSING:
            self.emit(ScriptEvent("runtime_exception", "too many programs at once: refused", 0, 0))
            return
        self._parsing.append(_PARSER.submit(compiled))

    def _compile(self, text: str) -> Program | ScriptEvent:
        """The program, ready to run, or the event that refuses it (any thread may run this)."""
        try:
            return Program(parse_program(text), self)
        except ScriptFault as fault:
            return ScriptEvent("runtime_exception", fault.text, fault.line, fault.column)
        except PROGRAM_ERRORS as exc:  # nested past Python's limits, a number of 5,000 digits
            return ScriptEvent("runtime_exception", f"syntax_error: {runtime_text(exc)}", 0, 0)

    def _start_parsed(self) -> None:
        """Start the programs read in the background, in the order they came."""
        while self._parsing and self._parsing[0].done():
            self._start(self._parsing.popleft().result())

    def _start(self, compiled: Program | ScriptEvent) -> Program | None:
        if isinstance(compiled, ScriptEvent):
            self.emit(compiled)
            return None
        program, script = compiled, compiled.script
        if script.secondary:
            for _ in range(SECONDARY_STEPS):
                program.advance(0.0)
                if program.finished:
                    break
            return program
        if not self.can_move():
            self.emit(ScriptEvent("runtime_exception", NOT_READY, program=program.name))
            return None
        if self.program is not None:
            self.stop_program()
        self.program, self.paused = program, False
        self._program_bits()
        self._runstate("start")
        names = global_names(script)  # the Global Variables Setup message lists them
        self.emit(ScriptEvent("program_started", program.name, program=program.name, names=names))
        program.advance(0.0)  # runs at once up to its first wait, as the controller does
        if program.finished:
            self._end_program()
        return program

    def _end_program(self) -> None:
        program, self.program = self.program, None
        if program is not None:
            program.stop()  # its threads and sockets end with it
        motion = self.arm.motion
        if motion is not None and (motion.holds or program is None or program.fault is not None):
            self.arm.stop(getattr(motion, "a", 1.4))  # a held speed or a failed move decelerates
        self.paused = False
        self._program_bits()
        self._runstate("fault" if program is not None and program.fault is not None else "stop")
        name = program.name if program is not None else ""
        self.emit(ScriptEvent("program_stopped", name, program=name))

    def emit(self, event: ScriptEvent) -> None:
        if event.kind == "runtime_exception":  # said in serve's log too: a client may not be listening
            where = f" at line {event.line}:{event.column}" if event.line else ""
            text = safe_text(event.text[:200])  # a program's own text: controls and undecodable bytes
            log.warning("program %s%s: %s", safe_text(event.program) or "refused", where, text)
        self.events.append(event)

    def drain_events(self) -> list[ScriptEvent]:
        """The events since the last call, oldest first (the servers send them)."""
        out = list(self.events)
        self.events.clear()
        return out

    def apply_inputs(self, inputs: Mapping[str, Any]) -> None:
        """A data package from a client: read-backs, then what the outputs reflect."""
        values = self.values
        for name in inputs:
            self.inputs_seen[name] = self.time  # for a program's rtde_set_watchdog
        for name, value in inputs.items():
            if name in values and name not in self.functions:
                values[name] = value  # input registers and the like read back as outputs
        for group in ("standard", "configurable", "tool"):
            mask = inputs.get(f"{group}_digital_output_mask")
            if mask:
                self._set_digital(group, mask, inputs.get(f"{group}_digital_output", 0))
        if inputs.get("speed_slider_mask") and "speed_slider_fraction" in inputs:
            slider = fraction(inputs["speed_slider_fraction"])  # NaN and inf ignored, the rest clamped
            if slider is not None:
                values["target_speed_fraction"] = slider
        mask = inputs.get("standard_analog_output_mask")
        if mask:
            types = inputs.get("standard_analog_output_type", 0)
            io_types = values.get("analog_io_types", 0)
            for i, select in enumerate(_ANALOG_OUT_SELECT):
                if mask & select:
                    level = fraction(inputs.get(f"standard_analog_output_{i}"))
                    if level is not None:
                        values[f"standard_analog_output{i}"] = level
                    voltage = _ANALOG_OUT_VOLTAGE[i]
                    io_types = (io_types | voltage) if types & select else (io_types & ~voltage)
            values["analog_io_types"] = int(io_types)

    def set_runstate(self, group: str, pin: int, state: int) -> None:
        """How a digital output follows the program from now on (set_runstate_*_output_to_value)."""
        self.runstate_outputs[(group, pin)] = state
        self._runstate("running" if self.program is not None else "stop", only=(group, pin))

    def _runstate(self, event: str, only: tuple[str, int] | None = None) -> None:
        """A program started, runs, stopped or ended unscheduled (a runtime exception): the outputs
        whose runstate choice says so change (runstate.py)."""
        powered = self.robot_mode in (RobotMode.IDLE, RobotMode.RUNNING)
        for (group, pin), level in runstate.levels(self.runstate_outputs, event, powered, only):
            self._set_digital(group, 1 << pin, int(level) << pin)

    def _set_digital(self, group: str, mask: int, bits: int) -> None:
        shift = _SHIFT[group]
        current = self.values.get("actual_digital_output_bits", 0)
        updated = (current & ~(mask << shift)) | ((bits & mask) << shift)
        self.values["actual_digital_output_bits"] = updated
        if group == "configurable" and "actual_configurable_digital_output_bits" in self.values:
            self.values["actual_configurable_digital_output_bits"] = updated >> shift & 0xFF


def fraction(value: Any) -> float | None:
    """An RTDE input meant as a fraction: clamped to [0, 1] as the controller does; NaN or inf ignored."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return min(1.0, max(0.0, number)) if math.isfinite(number) else None
