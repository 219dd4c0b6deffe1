"""JSON Lines from numpy columns without a Python object per value.

Turning every value into a Python float and every row into a dict costs more than
writing the JSON. Instead orjson writes each kind of column (floats, signed and
unsigned integers, bools) as one numpy matrix in C, and one format string per row
puts the names, brackets and values in place. The text is the same as orjson
writing the row dicts: same keys in the same order, vectors as lists, the same
shortest round-trip floats, NaN and infinities as null.
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Mapping
from typing import Any

_KINDS = ("float64", "int64", "uint64", "bool")


def _kind(column: Any) -> str:
    kind = column.dtype.kind
    if kind == "f":
        return "float64"
    if kind == "b":
        return "bool"
    return "uint64" if kind == "u" and column.dtype.itemsize == 8 else "int64"


class RowFormat:
    """The plan for one set of column names and dtypes: groups, value order, row format."""

    def __init__(self, columns: Mapping[str, Any]) -> None:
        import orjson

        self.key = _key(columns)
        self._dumps = orjson.dumps
        self._option = orjson.OPT_SERIALIZE_NUMPY
        self.groups: dict[str, list[str]] = {k: [] for k in _KINDS}
        for name, column in columns.items():
            self.groups[_kind(column)].append(name)
        self.groups = {k: names for k, names in self.groups.items() if names}
        slot: dict[str, int] = {}  # a column's first value's index in one row's values
        index = 0
        for names in self.groups.values():
            for name in names:
                slot[name] = index
                index += _width(columns[name])
        text: list[bytes] = []
        order: list[int] = []
        pending = b"{"
        for name, column in columns.items():
            key = pending + orjson.dumps(name) + b":"
            width, first = _width(column), slot[name]
            if column.ndim == 1:
                text.append(key)
                order.append(first)
                pending = b","
                continue
            for i in range(width):
                text.append(key + b"[" if i == 0 else b",")
                order.append(first + i)
            pending = b"],"
        tail = pending[:-1] + b"}"
        self.format = b"".join(t.replace(b"%", b"%%") + b"%b" for t in text) + tail
        self._pick = _picker(order)

    def lines(self, columns: Mapping[str, Any]) -> bytes:
        """Every row as one JSON object per line, newline-terminated."""
        import numpy as np

        rows = len(next(iter(columns.values())))
        if rows == 0:
            return b""
        parts = []
        for kind, names in self.groups.items():
            matrix = np.concatenate([columns[n].reshape(rows, -1) for n in names], axis=1).astype(kind)
            text = self._dumps(matrix, option=self._option)
            parts.append(text[2:-2].split(b"],["))
        fmt, pick = self.format, self._pick
        if len(parts) == 1:
            out = [fmt % pick(row.split(b",")) for row in parts[0]]
        else:
            out = [fmt % pick(b",".join(row).split(b",")) for row in zip(*parts, strict=True)]
        return b"\n".join(out) + b"\n"


def _width(column: Any) -> int:
    return 1 if column.ndim == 1 else int(column.shape[1])


def _picker(order: list[int]) -> Callable[[list[bytes]], tuple[bytes, ...]]:
    if order == list(range(len(order))):
        return tuple
    if len(order) == 1:
        only = order[0]
        return lambda values: (values[only],)
    return operator.itemgetter(*order)  # type: ignore[return-value]


def _key(columns: Mapping[str, Any]) -> tuple[tuple[str, str, tuple[int, ...]], ...]:
    return tuple((n, c.dtype.str, c.shape[1:]) for n, c in columns.items())


def fits(columns: Mapping[str, Any]) -> bool:
    """Whether the fast path can write these: numbers and bools, scalars or vectors; orjson installed."""
    try:
        import orjson  # noqa: F401
    except ImportError:
        return False
    return bool(columns) and all(
        c.dtype.kind in "fiub" and (c.ndim == 1 or (c.ndim == 2 and c.shape[1] > 0)) for c in columns.values()
    )


def formatter() -> Callable[[Mapping[str, Any]], bytes]:
    """A function columns -> JSON Lines bytes, re-planning only when the columns change."""
    plan: list[RowFormat] = []

    def lines(columns: Mapping[str, Any]) -> bytes:
        if not plan or plan[0].key != _key(columns):
            plan[:] = [RowFormat(columns)]
        return plan[0].lines(columns)

    return lines
