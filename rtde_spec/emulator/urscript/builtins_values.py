"""The Script Directory's urmath functions that make a value rather than compute one from a pose:
random() and make_list(length, initial_value, capacity); and get_rtde_value(name), an RTDE
output's value as the RTDE server sends it.

make_list's elements are copies of initial_value (URScript's values are values: changing one
element of a list of structs changes no other). The emulator has no list methods that grow or
shrink a list, so capacity is checked (not less than length) and not kept.
"""

from __future__ import annotations

import copy
import random as _random
from collections.abc import Callable
from typing import Any

from rtde_spec.emulator.urscript.calls import Pose, arg
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.matrices import MAX_ELEMENTS
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
VALUES: dict[str, Callable[[Runner, Stmt, Args, Kwargs], Any]] = {}
_builtin = registrar(VALUES)
_RANDOM = _random.Random()  # the emulator's own generator: a program's draws leave Python's alone


@_builtin("random")
def _draw(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    """A pseudo-random float from 0 to 1 (the Script Directory's urmath random())."""
    return _RANDOM.random()


def _count(stmt: Stmt, value: Any, name: str) -> int:
    if type(value) is not int or not 0 <= value <= MAX_ELEMENTS:
        raise ScriptFault(
            f"{stmt.name}: {name} must be an int of 0 to {MAX_ELEMENTS}, not {value!r}", stmt.line, 1
        )
    return value


@_builtin("make_list")
def _make_list(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[Any]:
    """`length` copies of `initial_value`: make_list(5, "a") is ["a", "a", "a", "a", "a"]. A list
    (not a pose) as the initial value is refused: "Creation list of list with this function is not supported
    (they are matrices in URScript)" (the Script Directory)."""
    length = _count(stmt, arg(stmt, args, kwargs, 0, "length"), "length")
    initial = arg(stmt, args, kwargs, 1, "initial_value")
    capacity = _count(stmt, arg(stmt, args, kwargs, 2, "capacity", length), "capacity")
    if isinstance(initial, list) and not isinstance(initial, Pose):
        what = "a list of lists is a matrix in URScript"
        raise ScriptFault(f"{stmt.name}: initial_value cannot be an array ({what})", stmt.line, 1)
    if capacity < length:
        raise ScriptFault(f"{stmt.name}: capacity {capacity} is less than length {length}", stmt.line, 1)
    if length and _elements(initial, MAX_ELEMENTS // length) * length > MAX_ELEMENTS:
        what = f"{length} of this initial value hold over {MAX_ELEMENTS} elements"
        raise ScriptFault(f"{stmt.name}: {what} (a value holds at most that)", stmt.line, 1)
    if isinstance(initial, (dict, Pose)):  # a struct or pose: each element its own
        return [copy.deepcopy(initial) for _ in range(length)]
    return [initial] * length


@_builtin("get_rtde_value")
def _rtde_value(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    """An RTDE output of this controller by its name, as RTDE clients receive it (a vector as a
    list). Undocumented in the editions on hand: UR's impedance-control example reads its own
    timing with get_rtde_value("actual_execution_time")."""
    name = arg(stmt, args, kwargs, 0, "name")
    outputs = getattr(runner.robot, "outputs", runner.robot.values)
    if not isinstance(name, str) or name not in outputs or name not in runner.robot.values:
        raise ScriptFault(f"{stmt.name}: no RTDE output {str(name)[:60]!r} on this controller", stmt.line, 1)
    value = runner.robot.values[name]
    return list(value) if isinstance(value, (tuple, list)) else value


def _elements(value: Any, budget: int) -> int:
    """The elements `value` holds through its lists and struct fields (1 for a number or a text),
    counted no further than past `budget`: make_list's copies stay within what a value may hold."""
    count, stack = 0, [value]
    while stack and count <= budget:
        item = stack.pop()
        if isinstance(item, list):
            stack.extend(item)
        elif isinstance(item, dict):
            stack.extend(item.values())
        else:
            count += 1
    return count
