"""Rows of the capture tables from decoded messages: flat, typed so every writer takes them.

Two kinds of value need care on their way to a table:
- text that is not UTF-8 (the primary codec keeps such bytes as surrogate escapes,
  which no UTF-8 writer accepts): the text column holds it with U+FFFD replacement
  characters and `<name>_raw` beside it the original bytes in hex (empty when the text
  is valid), so the column set of a table never depends on the data;
- unsigned 64-bit fields (the spec's bound 2^64 - 1): numpy uint64 values, so Parquet
  and Arrow make a uint64 column and a value of 2^63 or more fits it.
"""

from __future__ import annotations

import json
import types
import typing
from functools import cache
from typing import TYPE_CHECKING, Any

from rtde_spec.output.base import plain

if TYPE_CHECKING:
    from pydantic import BaseModel

    from rtde_spec.wire.primary_base import PrimaryPart

U64_MAX = (1 << 64) - 1
RAW = "_raw"


def text_columns(name: str, value: str | bytes) -> dict[str, str]:
    """`name`: the text (U+FFFD where bytes are not UTF-8); `name_raw`: those bytes in hex, or ''."""
    raw = value if isinstance(value, bytes) else value.encode("utf-8", "surrogateescape")
    try:
        return {name: raw.decode("utf-8"), name + RAW: ""}
    except UnicodeDecodeError:
        return {name: raw.decode("utf-8", "replace"), name + RAW: raw.hex()}


@cache
def uint64_fields(cls: type[BaseModel]) -> frozenset[str]:
    """The fields of a generated model whose values reach 2^64 - 1 (the spec's uint64)."""
    return frozenset(name for name, info in cls.model_fields.items() if U64_MAX in _bounds(info.annotation))


def _bounds(tp: Any) -> set[int]:
    found: set[int] = set()
    for arg in typing.get_args(tp):
        found |= _bounds(arg)
    for meta in getattr(tp, "__metadata__", ()):
        for item in getattr(meta, "metadata", [meta]):
            le = getattr(item, "le", None)
            if isinstance(le, int):
                found.add(le)
    return found


@cache
def column_types(cls: type[BaseModel]) -> dict[str, str]:
    """The type of each column `flatten_part` makes of a `cls` (numpy codes, "str"), for the
    columns a batch may hold only nulls in: a field the controller's version does not send.
    What has no one type (a union) is left out: its column is typed by its values."""
    out: dict[str, str] = {}
    unsigned = uint64_fields(cls)
    for key, info in cls.model_fields.items():
        if key not in ("extra", "missing"):
            _column_type(out, key, info.annotation, key in unsigned)
    return out


def _column_type(out: dict[str, str], name: str, annotation: Any, wide: bool) -> None:
    from pydantic import BaseModel

    tp, length = _bare(annotation)
    args = typing.get_args(tp)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        unsigned = uint64_fields(tp)
        for key, info in tp.model_fields.items():
            _column_type(out, f"{name}_{key}", info.annotation, key in unsigned)
    elif typing.get_origin(tp) is tuple and length is not None and args[1:] == (Ellipsis,):
        if _bare(args[0])[0] is str:  # texts: one JSON column
            out[name] = "str"
        else:
            for i in range(length):
                _column_type(out, f"{name}_{i}", args[0], wide)
    elif typing.get_origin(tp) is list or tp is bytes:
        out[name] = "str"  # JSON text, hex
    elif isinstance(tp, type) and issubclass(tp, str):
        out[name] = out[name + RAW] = "str"
    elif tp is bool:
        out[name] = "b1"
    elif isinstance(tp, type) and issubclass(tp, int):
        out[name] = "u8" if wide else "i8"
    elif tp is float:
        out[name] = "f8"


def _bare(annotation: Any) -> tuple[Any, int | None]:
    """An annotation without Optional and Annotated, and the fixed length its metadata gives."""
    length = None
    tp = annotation
    while True:
        origin = typing.get_origin(tp)
        if origin is typing.Annotated:
            items = [i for m in tp.__metadata__ for i in getattr(m, "metadata", [m])]
            low = [i.min_length for i in items if getattr(i, "min_length", None) is not None]
            high = [i.max_length for i in items if getattr(i, "max_length", None) is not None]
            if low and high and low[0] == high[0]:
                length = low[0]
            tp = typing.get_args(tp)[0]
        elif origin in (typing.Union, types.UnionType):
            options = [a for a in typing.get_args(tp) if a is not type(None)]
            if len(options) != 1:
                return None, None  # a union: no one type
            tp = options[0]
        else:
            return tp, length


def _wide(value: Any) -> Any:
    import numpy as np

    return np.uint64(value) if isinstance(value, int) and 0 <= value <= U64_MAX else value


def flatten_part(part: PrimaryPart) -> dict[str, Any]:
    """A sub-package or message as one flat row: groups and vectors of a fixed length (tuples)
    spread into numbered columns; a list, whose length varies from message to message (program
    threads, variable values), is one JSON column, so the table's columns never depend on it."""
    from pydantic import BaseModel  # loaded with the primary models that reach here

    out: dict[str, Any] = {}

    def put(prefix: str, value: Any, wide: bool) -> None:
        if isinstance(value, BaseModel):
            unsigned = uint64_fields(type(value))
            for key in type(value).model_fields:
                put(f"{prefix}_{key}", getattr(value, key), key in unsigned)
        elif isinstance(value, list):
            dumped = [v.model_dump(mode="json") if isinstance(v, BaseModel) else v for v in value]
            out[prefix] = json.dumps(plain(dumped))
        elif isinstance(value, tuple) and value and not isinstance(value[0], (str, dict)):
            for i, item in enumerate(value):
                put(f"{prefix}_{i}", item, wide)
        elif isinstance(value, (list, tuple, dict)):
            out[prefix] = json.dumps(plain(value))
        elif isinstance(value, (bytes, bytearray)):
            out[prefix] = bytes(value).hex()
        elif isinstance(value, str):
            out.update(text_columns(prefix, value))
        else:
            out[prefix] = _wide(value) if wide else value

    unsigned = uint64_fields(type(part))
    for key, value in part.values().items():
        put(key, value, key in unsigned)
    return out


def wide_values(values: dict[str, Any], codec: Any) -> dict[str, Any]:
    """Values of an RTDE data package with its recipe's UINT64 fields as numpy uint64."""
    if codec is None:
        return values
    unsigned = {item.name for item in codec.items if item.wire.element == "uint64"}
    if not unsigned:
        return values
    return {name: _wide(v) if name in unsigned else v for name, v in values.items()}
