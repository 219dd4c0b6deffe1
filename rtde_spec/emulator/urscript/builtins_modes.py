"""The built-ins that set the arm's modes and settings: force, teach and freedrive modes (which the
emulator approximates: it records the mode and holds the arm, since it models no forces), the tool
voltage and the payload, a protective stop, and what a simulator has besides: set_pos (the joints
placed at once) and time (a clock's reading). What a program sets that no RTDE output shows is
kept with the program (`settings_of`), so it ends with it; the modes show in the Robot Mode Data's
control mode (`control_mode`), the tool voltage and payload in their RTDE outputs.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from rtde_spec._generated.enums import ControlMode, RobotErrorCode, SafetyMode
from rtde_spec.emulator.urscript.calls import arg, number, six
from rtde_spec.emulator.urscript.events import ScriptEvent
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
Builtin = Callable[[Runner, Stmt, Args, Kwargs], Any]
MODES: dict[str, Builtin] = {}


_builtin = registrar(MODES)


def settings_of(runner: Runner) -> dict[str, Any]:
    """What a program set that no RTDE output shows (modes, watchdogs): kept with the program."""
    settings = getattr(runner, "settings", None)
    if settings is None:
        settings = {}
        runner.settings = settings  # type: ignore[attr-defined]
    return settings


def _mode(name: str, value: Any) -> Builtin:
    def set_mode(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
        settings_of(runner)[name] = value
        if name == "_freedrive" and value:
            runner.robot.arm.halt()

    return set_mode


def control_mode(program: object) -> int:
    """The control mode a running program's modes put the arm in (the Robot Mode Data's
    control_mode): TEACH in freedrive or teach mode, FORCE in force mode, TORQUE while
    direct_torque is called every control step (a step without it is position control again, as
    on a robot), else POSITION. A program that ends takes its modes with it, as the controller
    ends them with the program."""
    settings = getattr(program, "settings", None) or {}
    torque = settings.get("_direct_torque")
    if torque is not None:
        step = 1.0 / float(getattr(getattr(program, "robot", None), "base_hz", 500))
        if float(getattr(program, "clock", 0.0)) - torque[0] <= step * 1.5:
            return int(ControlMode.TORQUE)
    if settings.get("_freedrive"):
        return int(ControlMode.TEACH)
    if settings.get("_force_mode"):
        return int(ControlMode.FORCE)
    return int(ControlMode.POSITION)


MODES["force_mode"] = _mode("_force_mode", 1)
MODES["end_force_mode"] = _mode("_force_mode", 0)
MODES["teach_mode"] = _mode("_freedrive", 1)
MODES["freedrive_mode"] = _mode("_freedrive", 1)
MODES["end_teach_mode"] = _mode("_freedrive", 0)
MODES["end_freedrive_mode"] = _mode("_freedrive", 0)
for _name in (
    "force_mode_set_damping", "force_mode_set_gain_scaling", "zero_ftsensor", "ft_rtde_input_enable",
    "enable_external_ft_sensor", "set_safety_mode_transition_hardness",
    "tool_wrench_limit_disable",
):  # fmt: skip
    MODES[_name] = _mode(f"_{_name}", 1)
CLOCKS = (0, 2)  # time(mode): the controller's time since it started, the system time (1 is reserved)


@_builtin("motion_version_set")
def _motion_version(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    version = arg(stmt, args, kwargs, 0, "version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise ScriptFault(f"{stmt.name}: version must be a positive int, not {version!r}", stmt.line, 1)
    settings_of(runner)["_motion_version"] = version  # one planner in the emulator: recorded


@_builtin("set_pos")
def _set_pos(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """The simulated arm's joints set at once (no motion), within the arm model's limits."""
    arm = runner.robot.arm
    q = six(stmt, arg(stmt, args, kwargs, 0, "q"), "q")
    for joint, (value, (low, high)) in enumerate(zip(q, arm.model.joint_limits, strict=True)):
        if not low <= value <= high:
            raise ScriptFault(f"{stmt.name}: joint {joint} at {value:g} rad is past its limits", stmt.line, 1)
    arm.place(q)


@_builtin("time")
def _time(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> dict[str, int]:
    """struct(sec, nanosec) of time(mode=0) (the e-Series Script Directory): mode 0 the time since
    the controller started (monotonic; the emulator's, as RTDE's timestamp), 2 the system time
    (GMT, seconds since 1970), 1 reserved."""
    mode = arg(stmt, args, kwargs, 0, "mode", 0)
    if type(mode) is not int or mode not in CLOCKS:
        raise ScriptFault(
            f"{stmt.name}: mode must be 0 (controller) or 2 (system time), not {mode!r}", stmt.line, 1
        )
    if mode == 0:
        nanoseconds = round(float(getattr(runner.robot, "time", 0.0)) * 1e9)
    else:
        nanoseconds = time.time_ns()
    return {"sec": nanoseconds // 1_000_000_000, "nanosec": nanoseconds % 1_000_000_000}


TOOL_VOLTAGES = (0, 12, 24)  # what the tool connector supplies (Script Manual, set_tool_voltage)


@_builtin("set_tool_voltage")
def _tool_voltage(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """The tool connector's supply, shown as RTDE's tool_output_voltage (and the primary Tool Data).
    URCL's driver sends it as a float (24.0): a whole number of volts is taken in either type."""
    volts = number(stmt, arg(stmt, args, kwargs, 0, "voltage"), "voltage")
    if volts not in TOOL_VOLTAGES:
        raise ScriptFault(
            f"{stmt.name}: voltage must be 0, 12 or 24, not {volts:g}", stmt.line, stmt.column or 1
        )
    settings_of(runner)["_set_tool_voltage"] = int(volts)
    runner.robot.values["tool_output_voltage"] = int(volts)


def _three(stmt: Stmt, value: Any, name: str, count: int) -> tuple[float, ...]:
    if not isinstance(value, list) or len(value) != count:
        raise ScriptFault(f"{stmt.name}: {name} must be {count} numbers", stmt.line, stmt.column or 1)
    return tuple(number(stmt, v, name) for v in value)


@_builtin("set_target_payload", "set_payload_inertia")
def _target_payload(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """Mass, centre of gravity and inertia, shown as RTDE's payload, payload_cog and payload_inertia
    at once (the transition time is not modelled)."""
    values = runner.robot.values
    if stmt.name == "set_payload_inertia":
        values["payload_inertia"] = _three(stmt, arg(stmt, args, kwargs, 0, "inertia"), "inertia", 6)
        return
    mass = number(stmt, arg(stmt, args, kwargs, 0, "m"), "m")
    if mass < 0:
        raise ScriptFault(f"{stmt.name}: a negative mass", stmt.line, stmt.column or 1)
    cog = _three(stmt, arg(stmt, args, kwargs, 1, "cog"), "cog", 3)
    inertia = _three(stmt, arg(stmt, args, kwargs, 2, "inertia", [0.0] * 6), "inertia", 6)
    number(stmt, arg(stmt, args, kwargs, 3, "transition_time", 0.0), "transition_time")
    values.update(payload=mass, payload_cog=cog, payload_inertia=inertia)


@_builtin("protective_stop")
def _protective_stop(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """The stop, and the error code a controller reports for it: C209A0 ('A protective stop was
    triggered'), a warning (URCL's tests against URSim: test_ur_driver.cpp read_error_code,
    test_primary_client.cpp 'warning level error code')."""
    stop = getattr(runner.robot, "protective_stop", None)
    if stop is not None:
        new = int(runner.robot.values.get("safety_mode", 0)) != SafetyMode.PROTECTIVE_STOP
        stop()
        if new:
            code = int(RobotErrorCode.PROTECTIVE_STOP_TRIGGERED)
            runner.robot.emit(ScriptEvent("error_code", "", code=code, argument=0, warning=True))
