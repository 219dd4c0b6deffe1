"""The Script Directory's readings of the arm and tool a program asks for (force(), the joint and
tool temperatures, the tool's current and accelerometer) and the flags (set_flag/get_flag, kept
between program runs): each reading is the RTDE output that carries it, so a program and an RTDE
client see one value. Also settings a program reads back (gravity, the base's acceleration) and
the Modbus calls that only steer how a signal is polled.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from rtde_spec.emulator.urscript.builtins_io import _signal, _signal_name
from rtde_spec.emulator.urscript.builtins_modes import settings_of
from rtde_spec.emulator.urscript.calls import _is_number, arg, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
READINGS: dict[str, Callable[[Runner, Stmt, Args, Kwargs], Any]] = {}
_builtin = registrar(READINGS)
FLAGS = 32  # get_flag/set_flag's n: 0 to 31
GRAVITY = (0.0, 0.0, 9.82)  # PolyScope's default installation: set_gravity([0.0, 0.0, 9.82])


def _index(stmt: Stmt, value: Any, name: str, count: int) -> int:
    if type(value) is not int or not 0 <= value < count:
        raise ScriptFault(
            f"{stmt.name}: {name} must be an int of 0 to {count - 1}, not {value!r}", stmt.line, 1
        )
    return value


@_builtin("force")
def _force(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    """The norm of Fx, Fy and Fz of get_tcp_force() (RTDE's actual_TCP_force), in N."""
    wrench = runner.robot.values.get("actual_TCP_force", (0.0,) * 6)
    return math.sqrt(sum(float(f) ** 2 for f in wrench[:3]))


@_builtin("get_joint_temp")
def _joint_temp(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    """Joint j's temperature (°C; j 0 the base, 5 the wrist before the flange): joint_temperatures."""
    j = _index(stmt, arg(stmt, args, kwargs, 0, "j"), "j", 6)
    return float(runner.robot.values.get("joint_temperatures", (0.0,) * 6)[j])


@_builtin("get_tool_temp")
def _tool_temp(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    return float(runner.robot.values.get("tool_temperature", 0.0))


@_builtin("get_tool_current")
def _tool_current(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    """In A, from RTDE's tool_output_current in the unit the spec gives it (mA)."""
    return float(runner.robot.values.get("tool_output_current", 0.0)) * _amperes_per_unit()


def _amperes_per_unit() -> float:
    from rtde_spec.metamodel.catalogue import Catalogue

    info = Catalogue.builtin().get("tool_output_current", "output")
    return {"mA": 1e-3, "A": 1.0}[(info.unit if info is not None else None) or "A"]


@_builtin("get_tool_accelerometer_reading")
def _accelerometer(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    return [float(v) for v in runner.robot.values.get("actual_tool_accelerometer", (0.0,) * 3)]


def _flags(runner: Runner) -> list[bool]:
    """The robot's flags: they outlive the program, as the controller keeps them between runs."""
    flags: list[bool] = vars(runner.robot).setdefault("script_flags", [False] * FLAGS)
    return flags


@_builtin("set_flag")
def _set_flag(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    n = _index(stmt, arg(stmt, args, kwargs, 0, "n"), "n", FLAGS)
    b = arg(stmt, args, kwargs, 1, "b")
    if not isinstance(b, bool):
        raise ScriptFault(f"{stmt.name}: b must be a bool, not {type_name(b)}", stmt.line, 1)
    _flags(runner)[n] = b


@_builtin("get_flag")
def _get_flag(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
    return _flags(runner)[_index(stmt, arg(stmt, args, kwargs, 0, "n"), "n", FLAGS)]


# --- settings a program reads back (recorded with the program; the arm's model does not use them) --


def _vector(stmt: Stmt, value: Any, name: str) -> list[float]:
    if not isinstance(value, list) or len(value) != 3 or not all(_is_number(v) for v in value):
        raise ScriptFault(f"{stmt.name}: {name} must be three numbers", stmt.line, 1)
    return [float(v) for v in value]


@_builtin("set_gravity")
def _set_gravity(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    settings_of(runner)["gravity"] = _vector(stmt, arg(stmt, args, kwargs, 0, "d"), "d")


@_builtin("get_gravity")
def _get_gravity(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    """What set_gravity last set (PolyScope's preamble sets the installation's), else the
    installation's default of 9.82 m/s² along Base z."""
    return list(settings_of(runner).get("gravity", GRAVITY))


@_builtin("set_base_acceleration")
def _set_base_acceleration(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    settings_of(runner)["base_acceleration"] = _vector(stmt, arg(stmt, args, kwargs, 0, "a"), "a")


@_builtin("get_base_acceleration")
def _get_base_acceleration(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    return list(settings_of(runner).get("base_acceleration", [0.0, 0.0, 0.0]))


@_builtin("high_holding_torque_disable", "high_holding_torque_enable")
def _holding_torque(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    settings_of(runner)["_high_holding_torque"] = stmt.name.endswith("enable")  # no joint model: recorded


# --- the Modbus calls that only steer the polling of a signal (no device is polled) ---------------


@_builtin("modbus_set_digital_input_action")
def _modbus_input_action(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """A digital input signal's action: "default" or "freedrive"."""
    name = _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name"))
    signal = _signal(runner, stmt, name)
    action = arg(stmt, args, kwargs, 1, "action")
    if signal["type"] != 0 or action not in ("default", "freedrive"):
        what = f'{name!r} must be a digital input and action "default" or "freedrive", not {action!r}'
        raise ScriptFault(f"{stmt.name}: {what}"[:200], stmt.line, 1)
    signal["action"] = action


@_builtin("modbus_request_update_signal_value")
def _modbus_request_update(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    _signal(runner, stmt, _signal_name(stmt, arg(stmt, args, kwargs, 0, "signal_name")))


@_builtin("modbus_reset_connection")
def _modbus_reset(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """Tear down and reconnect a device's signals: none has an error to wait out."""
    address = arg(stmt, args, kwargs, 0, "connection_id")
    blocking = arg(stmt, args, kwargs, 1, "is_blocking", True)
    if not isinstance(address, str) or not address or not isinstance(blocking, bool):
        raise ScriptFault(
            f"{stmt.name}: connection_id must be an IP address text, is_blocking a bool", stmt.line, 1
        )
