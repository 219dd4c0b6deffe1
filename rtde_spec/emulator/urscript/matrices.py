"""URScript's matrices, as the Script Manual's "Matrix and Array Expressions" defines them (3.14 / 5.9
on): a matrix is written as its rows, `[[1, 2], [3, 4], [5, 6]]` (3 x 2); `m[i, j]` reads or
writes the entry of row i, column j, both from 0; a matrix times a matrix (the first's columns the
second's rows) or times an array (as long as its rows) is the matrix product; a number with a
matrix applies to every entry. What the manual leaves out (a matrix plus a matrix) is a type
error, so a program the controller would refuse is not run here.

A matrix is a list of rows, so it is a value as arrays are: `m[0, 0] = 1` copies. Products run in
numpy; integer ones stay exact and URScript's 32-bit ints.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rtde_spec.emulator.urscript.nodes import ScriptFault

Scalar = Callable[[str, Any, Any, int, int], Any]  # values.arithmetic: one operation on plain values
INT_MIN, INT_MAX = -(1 << 31), (1 << 31) - 1
MAX_ELEMENTS = 1 << 16  # elements of one value, through its lists (evaluator.py holds values to it)


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def is_matrix(value: Any) -> bool:
    """One or more rows, each a list of the same one or more numbers."""
    if not isinstance(value, list) or not value or not isinstance(value[0], list):
        return False
    width = len(value[0])
    return width > 0 and all(isinstance(r, list) and len(r) == width and all(map(_number, r)) for r in value)


def size(matrix: list[list[Any]]) -> str:
    return f"{len(matrix)} x {len(matrix[0])}"


def describe(value: Any) -> str:
    """A value as a type error names it: a matrix with its size."""
    if is_matrix(value):
        return f"matrix {size(value)}"
    return "array" if isinstance(value, list) else type(value).__name__


def _check(matrix: Any, row: Any, column: Any, line: int, where: int) -> None:
    if not is_matrix(matrix):
        raise ScriptFault(f"Type error: [i, j] needs a matrix, not {describe(matrix)}", line, where)
    for index in (row, column):
        if not isinstance(index, int) or isinstance(index, bool):
            raise ScriptFault(f"Type error: an index must be an int, not {describe(index)}", line, where)
    if not (0 <= row < len(matrix) and 0 <= column < len(matrix[0])):
        raise ScriptFault(f"Index out of bounds: [{row}, {column}] (matrix of {size(matrix)})", line, where)


def cell(matrix: Any, row: Any, column: Any, line: int, where: int) -> Any:
    """`matrix[row, column]`: rows of one length and a number there are enough to read it at once
    (ur_rtde reads 36 entries in one control step); anything else takes the full checks."""
    if type(row) is int and type(column) is int and type(matrix) is list and 0 <= row < len(matrix):
        width = len(matrix[0]) if type(matrix[0]) is list else -1
        if 0 <= column < width and all(type(r) is list and len(r) == width for r in matrix):
            value = matrix[row][column]
            if type(value) in (int, float):
                return value
    _check(matrix, row, column, line, where)
    return matrix[row][column]


def with_cell(matrix: Any, row: Any, column: Any, new: Any, line: int, where: int) -> list[list[Any]]:
    """A copy of `matrix` with `matrix[row, column] = new`: an entry stays a number."""
    _check(matrix, row, column, line, where)
    if not _number(new):
        raise ScriptFault(f"Type error: a matrix entry must be a number, not {describe(new)}", line, where)
    copy = [list(r) for r in matrix]
    copy[row][column] = new
    return copy


def arithmetic(op: str, left: Any, right: Any, line: int, where: int, scalar: Scalar) -> Any:
    """`left op right` where one side is a matrix."""
    left_m, right_m = is_matrix(left), is_matrix(right)
    if op == "*" and left_m and (right_m or (isinstance(right, list) and right and all(map(_number, right)))):
        if len(left[0]) != len(right):
            raise ScriptFault(
                f"Type error: {describe(left)} * {describe(right)}: the columns of the first "
                "must be the rows of the second",
                line,
                where,
            )
        return product(left, right, line, where)
    if left_m and _number(right):
        return [scalar(op, row, right, line, where) for row in left]
    if right_m and _number(left):
        return [scalar(op, left, row, line, where) for row in right]
    raise ScriptFault(f"Type error: {describe(left)} {op} {describe(right)}", line, where)


def product(left: list[list[Any]], right: list[Any], line: int, where: int) -> list[Any]:
    """The matrix product (an array when `right` is one), no bigger than a value may be; ints
    stay exact and 32-bit (each split in 16-bit halves, so int64 never overflows on the way)."""
    rows, columns = len(left), (len(right[0]) if isinstance(right[0], list) else 1)
    if rows * columns > MAX_ELEMENTS:
        raise ScriptFault(
            f"Type error: a product of {rows} x {columns} entries (a value holds at most {MAX_ELEMENTS})",
            line,
            where,
        )
    a, b = np.array(left), np.array(right)
    if a.dtype.kind == "i" and b.dtype.kind == "i":  # every entry an int (a bool is no number here)
        out = _exact(a.astype(np.int64), b.astype(np.int64))
        if np.any(out < INT_MIN) or np.any(out > INT_MAX):
            raise ScriptFault("Integer overflow: URScript's int is 32 bits", line, where)
        return [[int(v) for v in r] for r in out] if out.ndim == 2 else [int(v) for v in out]
    out = np.matmul(a.astype(float), b.astype(float))
    return [[float(v) for v in r] for r in out] if out.ndim == 2 else [float(v) for v in out]


def _exact(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a @ b of 32-bit ints, exactly: by 16-bit halves, each partial product fits int64."""
    a_high, a_low, b_high, b_low = a >> 16, a & 0xFFFF, b >> 16, b & 0xFFFF
    high = np.matmul(a_high, b_high).astype(object)
    middle = (np.matmul(a_high, b_low) + np.matmul(a_low, b_high)).astype(object)
    return np.asarray(high * (1 << 32) + middle * (1 << 16) + np.matmul(a_low, b_low).astype(object))


def transpose(value: Any, line: int, where: int) -> list[Any]:
    """Rows as columns; an array is one column and a matrix of one column an array, as the Script
    Directory's examples go (transpose([1,2,3]) is [[1],[2],[3]], and back)."""
    if isinstance(value, list) and value and all(_number(v) for v in value):
        return [[v] for v in value]
    if not is_matrix(value):
        raise ScriptFault(
            f"Type error: transpose needs a matrix or an array, not {describe(value)}", line, where
        )
    if len(value[0]) == 1:
        return [row[0] for row in value]
    return [list(column) for column in zip(*value, strict=True)]


def inverse(value: Any, line: int, where: int) -> list[list[float]]:
    """The inverse of a square, non-singular matrix (inv of a pose is pose_inv)."""
    if not is_matrix(value) or len(value) != len(value[0]):
        raise ScriptFault(
            f"Type error: inv needs a square matrix or a pose, not {describe(value)}", line, where
        )
    matrix = np.array(value, dtype=float)
    if not np.all(np.isfinite(matrix)) or np.linalg.cond(matrix) > 1e12:
        raise ScriptFault(f"inv: the matrix is singular ({size(value)})", line, where)
    return [[_tidy(v) for v in row] for row in np.linalg.inv(matrix)]


def _tidy(value: float) -> float:
    """-0.0 as 0.0, as a controller prints an inverse's zeros."""
    return float(value) + 0.0
