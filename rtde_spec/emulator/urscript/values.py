"""Comparisons, truth and indexing of URScript values, typed as the controller types them.

A condition must be a bool (the controller does not take 0 or an empty list for
False), values of different types do not compare, and an index is an int within the
array: each of these is a ScriptFault at the line and column, never a guess.
Arrays are values in URScript, so assigning `q[0] = 1` copies rather than changing
another variable that holds the same list.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

from rtde_spec.emulator.urscript import matrices
from rtde_spec.emulator.urscript.nodes import ScriptFault


class Pose(list[float]):
    """A p[...] value: six numbers, told apart from a joint list by movej/movel."""


def make_pose(values: list[Any], line: int, column: int) -> Pose:
    if len(values) != 6 or not all(_is_number(v) for v in values):
        raise ScriptFault("a pose needs six numbers: p[x, y, z, rx, ry, rz]", line, column)
    return Pose(float(v) for v in values)


INT_MIN, INT_MAX = -(1 << 31), (1 << 31) - 1  # URScript's int is 32 bits
MAX_TEXT = 1 << 20  # characters of one string (a program doubling a text must not take the memory)


_OPS: dict[str, Callable[[Any, Any], Any]] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
    "/": operator.truediv,
    "%": operator.mod,
}


def arithmetic(op: str, left: Any, right: Any, line: int, column: int) -> Any:
    if _is_number(left) and _is_number(right):
        if op in "/%" and right == 0:
            raise ScriptFault("Division by zero", line, column)
        try:
            result = _OPS[op](left, right)
        except OverflowError:
            raise ScriptFault("Number too large", line, column) from None
        if isinstance(result, int) and not isinstance(result, bool) and not INT_MIN <= result <= INT_MAX:
            raise ScriptFault("Integer overflow: URScript's int is 32 bits", line, column)
        return result
    if op == "+" and isinstance(left, str) and isinstance(right, str):
        if len(left) + len(right) > MAX_TEXT:
            raise ScriptFault(f"String too long (over {MAX_TEXT} characters)", line, column)
        return left + right
    if matrices.is_matrix(left) or matrices.is_matrix(right):
        return matrices.arithmetic(op, left, right, line, column, arithmetic)
    if op in "+-*/" and (isinstance(left, list) or isinstance(right, list)):
        return _elementwise(op, left, right, line, column)
    raise ScriptFault(f"Type error: {type_name(left)} {op} {type_name(right)}", line, column)


def _elementwise(op: str, left: Any, right: Any, line: int, column: int) -> list[Any]:
    """Arrays of numbers element by element (`q + qd * t`), a number applying to every element."""
    size = len(left) if isinstance(left, list) else len(right)
    if isinstance(left, list) and isinstance(right, list) and len(left) != len(right):
        raise ScriptFault(f"Type error: arrays of {len(left)} and {len(right)} elements", line, column)
    lefts = left if isinstance(left, list) else [left] * size
    rights = right if isinstance(right, list) else [right] * size
    if all(type(v) in _PLAIN for v in lefts) and all(type(v) in _PLAIN for v in rights):  # at C speed
        if op in "/%" and 0 in rights:
            raise ScriptFault("Division by zero", line, column)
        results = list(map(_OPS[op], lefts, rights))
        if all(type(r) is float or INT_MIN <= r <= INT_MAX for r in results):
            return results
    if not all(_is_number(v) for v in (*lefts, *rights)):
        raise ScriptFault(f"Type error: {type_name(left)} {op} {type_name(right)}", line, column)
    return [arithmetic(op, a, b, line, column) for a, b in zip(lefts, rights, strict=True)]


_PLAIN = (int, float)  # exact types (a bool is no number): element-wise at once


def float_text(value: float) -> str:
    """A float as to_str, str_cat and textmsg show it: "formatted with 6 decimals, and trailing
    zeros will be removed" (the Script Directory: to_str(2.123456123456) is "2.123456")."""
    if not math.isfinite(value):
        return f"{value:g}"
    text = f"{value:.6f}".rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


def type_name(value: Any) -> str:
    return {
        Pose: "pose",
        list: "array",
        bool: "bool",
        int: "int",
        float: "float",
        str: "string",
        dict: "struct",
    }.get(type(value), type(value).__name__)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def compare(op: str, left: Any, right: Any, line: int, column: int) -> bool:
    """`== != < <= > >=`: numbers with numbers; equality also for two values of one type."""
    if _is_number(left) and _is_number(right):
        ordered = {"<": left < right, "<=": left <= right, ">": left > right, ">=": left >= right}
        if op in ordered:
            return bool(ordered[op])
    elif op not in ("==", "!=") or type_name(left) != type_name(right):
        raise ScriptFault(f"Type error: {type_name(left)} {op} {type_name(right)}", line, column)
    equal = bool(left == right)
    return equal if op == "==" else not equal


def truth(value: Any, what: str, line: int, column: int) -> bool:
    """A bool, or the type error a controller gives for a condition or operand of another type."""
    if isinstance(value, bool):
        return value
    raise ScriptFault(f"Type error: {what} must be a bool, not {type_name(value)}", line, column)


def condition(value: Any, line: int, column: int) -> bool:
    """An `if`/`elif`/`while` condition: a bool, or a number (true unless 0), as the controller takes
    it: UR's client library writes `if has_qnear:` of a float in the ROS driver's program, and its
    tests run that against URSim. Anything else is the type error `truth` gives."""
    if type(value) in (int, float):
        return bool(value)
    return truth(value, "a condition", line, column)


def index(value: Any, position: Any, line: int, column: int) -> Any:
    """`value[position]` of an array or pose (`m[i, j]` of a matrix: matrices.cell)."""
    if not isinstance(value, list):
        raise ScriptFault(f"Type error: {type_name(value)} cannot be indexed", line, column)
    if not _is_number(position) or not isinstance(position, int):
        raise ScriptFault(f"Type error: an index must be an int, not {type_name(position)}", line, column)
    if not 0 <= position < len(value):
        raise ScriptFault(f"Index out of bounds: {position} (length {len(value)})", line, column)
    return value[position]


class Member(str):
    """A struct's field an assignment writes (`s.kp = ...`), among its subscripts."""


def replaced(value: Any, positions: list[Any], new: Any, line: int, column: int) -> Any:
    """A copy of `value` with the element at `positions` (one per subscript, a matrix's row and
    column a tuple, a struct's field a Member) set to `new`; a struct keeps the fields it has."""
    here = positions[0]
    if isinstance(here, Member):
        if not isinstance(value, dict) or here not in value:
            raise ScriptFault(f"Type error: {type_name(value)} has no field {here}", line, column)
        rest = new if len(positions) == 1 else replaced(value[here], positions[1:], new, line, column)
        return {**value, str(here): rest}
    if isinstance(here, tuple):  # m[i, j]: an entry, so the last subscript
        if len(positions) > 1:
            raise ScriptFault("Type error: a matrix entry cannot be indexed", line, column)
        return matrices.with_cell(value, here[0], here[1], new, line, column)
    index(value, here, line, column)  # the same checks as reading it
    copy = list(value)
    copy[here] = new if len(positions) == 1 else replaced(copy[here], positions[1:], new, line, column)
    return make_pose(copy, line, column) if isinstance(value, Pose) else copy
