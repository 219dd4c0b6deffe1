"""Typed global-variable values of Program State update messages.

Each value is a type byte then its data; top-level values end with a separator
byte. LIST and MATRIX nest (type, value) pairs without separators. The type
table, its codes and layouts come from the spec.

Hostile counts cannot make a decode allocate more than a fixed multiple of its
input: every LIST or MATRIX element takes at least one byte on the wire (its type
byte), so a count whose elements cannot fit in the bytes left is refused before
anything is built. A row of a 0-column matrix takes no bytes at all, so each such
row is charged one byte of the message's value bytes: all the empty rows of one
message together are at most as many as its value bytes. The multiple is that of
Python objects, not small: a value that is not shared (NONE, booleans and empty
strings are) is an object and its dict, ~300 bytes, for as few as 3 wire bytes (an
empty LIST), so a message of those peaks at ~150x its bytes (tests/test_primary.py);
a message is at most the codec's max size (1 MiB).
"""

from __future__ import annotations

import struct
from functools import cache
from typing import Any

from pydantic import BaseModel, ConfigDict

from rtde_spec._generated.constants import PRIMARY_BYTE_ORDER as ORDER
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.wire.model_types import WireText

MAX_DEPTH = 32  # nested lists deeper than this are refused, not recursed into
_set_dict = BaseModel.__dict__["__dict__"].__set__
_BOTH_SET = frozenset({"type", "value"})  # the fields set of every decoded value
_UNSET = frozenset({"__pydantic_extra__", "__pydantic_private__"})
_new = object.__new__


class VariableValue(BaseModel):
    """One value: `type` is the GlobalVariableType name; `value` depends on it.

    NONE: None; strings: str; POSE: 6 floats; BOOL: bool; NUM/FLOAT: float; INT: int;
    LIST: list of VariableValue; MATRIX: list of rows, each a list of VariableValue.
    """

    model_config = ConfigDict(frozen=True, ser_json_inf_nan="strings")  # as PrimaryModel's
    type: str
    value: (
        bool
        | int
        | float
        | WireText
        | tuple[float, ...]
        | list[VariableValue]
        | list[list[VariableValue]]
        | None
    ) = None

    def __getattr__(self, item: str) -> Any:
        """Decoded values leave pydantic's bookkeeping slots unset (as `PrimaryModel`s do): their values."""
        if item == "__pydantic_fields_set__":
            return set(_BOTH_SET)
        if item in _UNSET:
            return None
        return super().__getattr__(item)  # type: ignore[misc]


def _made(name: str, value: Any) -> VariableValue:
    """A decoded value, unvalidated (struct typed it): one allocation and one dict.

    Validating the value union per element costs most of a decode and ~2x the memory
    (benchmarks/faults_bombs.py); the primary tests check these equal validated twins.
    """
    obj = _new(VariableValue)
    _set_dict(obj, {"type": name, "value": value})
    return obj  # type: ignore[no-any-return]


class ValueTable:
    """Codes and layouts of the value types, built from spec data."""

    def __init__(
        self, value_types: list[Any], codes: dict[str, int], prims: dict[str, Any], separator: int
    ) -> None:
        self.by_code: dict[int, Any] = {}
        self.by_name: dict[str, tuple[int, Any]] = {}
        self.separator = separator
        self.prims = prims
        # values with no data, or only True/False, are shared: a list of them costs a pointer each
        self._shared: dict[tuple[str, Any], VariableValue] = {}
        for vt in value_types:
            self.by_code[codes[vt.name]] = vt
            self.by_name[vt.name] = (codes[vt.name], vt)
            if vt.kind == "none":
                self._shared[(vt.name, None)] = VariableValue(type=vt.name, value=None)
            elif vt.kind == "string":
                self._shared[(vt.name, "")] = _made(vt.name, "")
            elif vt.kind == "scalar" and vt.count == 1 and self.prims[vt.element].struct == "?":
                self._shared[(vt.name, False)] = _made(vt.name, False)
                self._shared[(vt.name, True)] = _made(vt.name, True)
        # fewest bytes one element of a LIST or MATRIX takes: its type byte and the smallest data
        self.min_element = 1 + min(self._min_data(vt) for vt in value_types)
        # code -> (name, kind, the struct of its data (scalar) or of its length prefix, count)
        self._plans: dict[int, tuple[str, str, struct.Struct, int]] = {
            code: (vt.name, vt.kind, self._data_struct(vt), vt.count) for code, vt in self.by_code.items()
        }

    def _data_struct(self, vt: Any) -> struct.Struct:
        if vt.kind == "none":
            return self._struct("")
        if vt.kind == "scalar":
            return self._struct(self.prims[vt.element].struct * vt.count)
        return self._prefix(vt.length)

    @cache  # noqa: B019 - one table per process
    def _struct(self, fmt: str) -> struct.Struct:
        return struct.Struct(ORDER + fmt)

    def _prefix(self, name: str) -> struct.Struct:
        return self._struct(self.prims[name].struct)

    def _min_data(self, vt: Any) -> int:
        """Fewest data bytes a value of this type has after its type byte."""
        if vt.kind == "none":
            return 0
        if vt.kind == "scalar":
            return self._struct(self.prims[vt.element].struct * vt.count).size
        return self._prefix(vt.length).size * (2 if vt.kind == "matrix" else 1)

    # --- decoding -----------------------------------------------------------

    def decode_all(self, buf: bytes, pos: int, end: int, field: str) -> list[VariableValue]:
        out = []
        budget = [end - pos]  # empty matrix rows left to build: one per value byte
        while pos < end:
            value, pos = self._decode_one(buf, pos, end, field, 0, budget)
            if pos >= end or buf[pos] != self.separator:
                raise DecodeError(
                    "global variable value not followed by its separator",
                    field=field,
                    offset=pos,
                    expected=f"0x{self.separator:02x}",
                    actual=f"0x{buf[pos]:02x}" if pos < end else "end of message",
                )
            pos += 1
            out.append(value)
        return out

    def _need(self, buf: bytes, pos: int, size: int, end: int, field: str) -> None:
        if end - pos < size:
            raise DecodeError(
                "global variable value runs past the message",
                field=field,
                offset=pos,
                expected=f"{size} bytes",
                actual=f"{end - pos} bytes",
            )

    def _check_count(
        self, kind: str, count: int, empty_rows: int, pos: int, end: int, field: str, budget: list[int]
    ) -> None:
        """Refuse a count whose elements cannot fit in the bytes left, before building any.

        `empty_rows` (rows of a 0-column matrix) take no bytes: they are charged to the
        message's budget instead, so they too stay within its size.
        """
        need = count * self.min_element
        if need > end - pos:
            raise DecodeError(
                f"{kind} of {count} elements cannot fit in the bytes left",
                field=field,
                offset=pos,
                expected=f">= {need} bytes ({count} x >= {self.min_element})",
                actual=f"{end - pos} bytes left",
            )
        if empty_rows:
            budget[0] -= empty_rows
            if budget[0] < 0:
                raise DecodeError(
                    f"matrix of {empty_rows} rows x 0 columns: more empty rows than the message has bytes",
                    field=field,
                    offset=pos,
                    expected=f"<= {budget[0] + empty_rows} empty rows",
                    actual=f"{empty_rows} rows",
                )

    def _decode_one(
        self, buf: bytes, pos: int, end: int, field: str, depth: int, budget: list[int]
    ) -> tuple[VariableValue, int]:
        if depth > MAX_DEPTH:
            raise DecodeError(
                "global variable values nest too deeply",
                field=field,
                offset=pos,
                expected=f"<= {MAX_DEPTH} levels",
            )
        if pos >= end:
            self._need(buf, pos, 1, end, field)
        code = buf[pos]
        plan = self._plans.get(code)
        if plan is None:
            raise DecodeError(
                f"unknown global variable type {code}",
                field=field,
                offset=pos,
                expected=", ".join(f"{c} ({v.name})" for c, v in self.by_code.items()),
            )
        name, kind, st, count = plan
        pos += 1
        size = st.size
        if kind == "none":
            return self._shared[(name, None)], pos
        if end - pos < size:
            self._need(buf, pos, size, end, field)
        if kind == "scalar":
            items = st.unpack_from(buf, pos)
            if count != 1:
                return _made(name, items), pos + size
            value = items[0]
            if type(value) is bool:
                return self._shared[(name, value)], pos + size
            return _made(name, value), pos + size
        (length,) = st.unpack_from(buf, pos)
        pos += size
        if kind == "string":
            if end - pos < length:
                self._need(buf, pos, length, end, field)
            if not length:
                return self._shared[(name, "")], pos
            return _made(name, str(buf[pos : pos + length], "utf-8", "surrogateescape")), pos + length
        if kind == "list":
            self._check_count("list", length, 0, pos, end, field, budget)
            items_out = []
            for _ in range(length):
                item, pos = self._decode_one(buf, pos, end, field, depth + 1, budget)
                items_out.append(item)
            return _made(name, items_out), pos
        # matrix: rows then columns, both of the length primitive
        self._need(buf, pos, size, end, field)
        (cols,) = st.unpack_from(buf, pos)
        pos += size
        self._check_count("matrix", length * cols, 0 if cols else length, pos, end, field, budget)
        rows = []
        for _ in range(length):
            row = []
            for _ in range(cols):
                item, pos = self._decode_one(buf, pos, end, field, depth + 1, budget)
                row.append(item)
            rows.append(row)
        return _made(name, rows), pos

    # --- encoding -----------------------------------------------------------

    def encode_all(self, values: list[VariableValue | dict[str, Any]], field: str) -> bytes:
        return b"".join(self._encode_one(v, field, 0) + bytes([self.separator]) for v in values)

    def _encode_one(self, item: VariableValue | dict[str, Any], field: str, depth: int) -> bytes:
        if isinstance(item, dict):  # from model_dump()
            item = VariableValue(**item)
        if depth > MAX_DEPTH:
            raise EncodeError("global variable values nest too deeply", field=field)
        entry = self.by_name.get(item.type)
        if entry is None:
            raise EncodeError(
                f"unknown global variable type {item.type!r}", field=field, expected=", ".join(self.by_name)
            )
        code, vt = entry
        head = bytes([code])
        value: Any = item.value
        try:
            if vt.kind == "none":
                return head
            if vt.kind == "scalar":
                st = self._struct(self.prims[vt.element].struct * vt.count)
                items = (value,) if vt.count == 1 else tuple(value)
                return head + st.pack(*items)
            prefix = self._prefix(vt.length)
            if vt.kind == "string":
                data = str(value).encode("utf-8", "surrogateescape")
                return head + prefix.pack(len(data)) + data
            if vt.kind == "list":
                return (
                    head
                    + prefix.pack(len(value))
                    + b"".join(self._encode_one(v, field, depth + 1) for v in value)
                )
            rows = value
            cols = len(rows[0]) if rows else 0
            if any(len(r) != cols for r in rows):
                raise EncodeError("matrix rows differ in length", field=field)
            body = b"".join(self._encode_one(v, field, depth + 1) for r in rows for v in r)
            return head + prefix.pack(len(rows)) + prefix.pack(cols) + body
        except (struct.error, TypeError) as exc:
            raise EncodeError(
                f"{item.type} value cannot be encoded: {exc}", field=field, actual=repr(value)
            ) from None
