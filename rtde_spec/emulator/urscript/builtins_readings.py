"""The Script Directory's readings of the arm and tool a program asks for (force(), the joint and
tool temperatures, the tool's current and accelerometer) and the flags (set_flag/get_flag, kept
between program runs): each reading is the RTDE output that carries it, so a program and an RTDE
client see one value.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from rtde_spec.emulator.urscript.calls import arg, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
READINGS: dict[str, Callable[[Runner, Stmt, Args, Kwargs], Any]] = {}
_builtin = registrar(READINGS)
FLAGS = 32  # get_flag/set_flag's n: 0 to 31


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
    """In A (RTDE's tool_output_current is in mA)."""
    return float(runner.robot.values.get("tool_output_current", 0.0)) / 1000.0


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
