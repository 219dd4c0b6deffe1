"""Comparisons, truth and indexing of URScript values, typed as the controller types them.

A condition must be a bool (the controller does not take 0 or an empty list for
False), values of different types do not compare, and an index is an int within the
array: each of these is a ScriptFault at the line and column, never a guess.
Arrays are values in URScript, so assigning `q[0] = 1` copies rather than changing
another variable that holds the same list.
"""

from __future__ import annotations

from typing import Any

from rtde_spec.emulator.urscript.calls import Pose, make_pose, type_name
from rtde_spec.emulator.urscript.nodes import ScriptFault


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


def index(value: Any, position: Any, line: int, column: int) -> Any:
    """`value[position]` of an array or pose."""
    if not isinstance(value, list):
        raise ScriptFault(f"Type error: {type_name(value)} cannot be indexed", line, column)
    if not _is_number(position) or not isinstance(position, int):
        raise ScriptFault(f"Type error: an index must be an int, not {type_name(position)}", line, column)
    if not 0 <= position < len(value):
        raise ScriptFault(f"Index out of bounds: {position} (length {len(value)})", line, column)
    return value[position]


def replaced(value: Any, positions: list[Any], new: Any, line: int, column: int) -> Any:
    """A copy of `value` with the element at `positions` (one per subscript) set to `new`."""
    index(value, positions[0], line, column)  # the same checks as reading it
    copy = list(value)
    here = positions[0]
    copy[here] = new if len(positions) == 1 else replaced(copy[here], positions[1:], new, line, column)
    return make_pose(copy, line, column) if isinstance(value, Pose) else copy
