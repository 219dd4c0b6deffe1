"""The record a data package decodes to: every value unpacked, vectors grouped on access.

A record is the flat tuple `struct` unpacks (so making one costs a single C call),
with one read-only attribute per recipe variable: scalars by index, vectors as a
slice of the tuple. It reads like a NamedTuple (`_fields`, `_asdict`, attribute
access by the spec's names) without regrouping 160 values per package.
"""

from __future__ import annotations

from collections.abc import Sequence
from operator import itemgetter
from typing import Any


class RecordBase(tuple):  # type: ignore[type-arg]
    """Base of every recipe's record class; the flat values are the tuple itself."""

    __slots__ = ()
    _fields: tuple[str, ...] = ()
    _getters: tuple[Any, ...] = ()

    def _asdict(self) -> dict[str, Any]:
        """Values by name, vectors as tuples."""
        return {name: get(self) for name, get in zip(self._fields, self._getters, strict=True)}

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v!r}" for k, v in self._asdict().items())
        return f"{type(self).__name__}({inner})"


def record_class(fields: Sequence[tuple[str, int, Any]], name: str = "Record") -> type[RecordBase]:
    """A record class for (name, element count, Python type) in wire order."""
    namespace: dict[str, Any] = {"__slots__": (), "__annotations__": {}}
    getters = []
    pos = 0
    for field, count, py_type in fields:
        getter = itemgetter(pos) if count == 1 else itemgetter(slice(pos, pos + count))
        getters.append(getter)
        namespace[field] = property(getter, doc=f"{field} ({py_type})")
        namespace["__annotations__"][field] = py_type
        pos += count
    namespace["_fields"] = tuple(f[0] for f in fields)
    namespace["_getters"] = tuple(getters)
    namespace["_size"] = pos
    return type(name, (RecordBase,), namespace)
