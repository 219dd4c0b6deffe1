"""Typed global-variable values of Program State update messages.

Each value is a type byte then its data; top-level values end with a separator
byte. LIST and MATRIX nest (type, value) pairs without separators. The type
table, its codes and layouts come from the spec.
"""

from __future__ import annotations

import struct
from functools import cache
from typing import Any

from pydantic import BaseModel, ConfigDict

from rtde_spec._generated.constants import PRIMARY_BYTE_ORDER as ORDER
from rtde_spec.errors import DecodeError, EncodeError

MAX_DEPTH = 32  # nested lists deeper than this are refused, not recursed into


class VariableValue(BaseModel):
    """One value: `type` is the GlobalVariableType name; `value` depends on it.

    NONE: None; strings: str; POSE: 6 floats; BOOL: bool; NUM/FLOAT: float; INT: int;
    LIST: list of VariableValue; MATRIX: list of rows, each a list of VariableValue.
    """

    model_config = ConfigDict(frozen=True)
    type: str
    value: (
        bool | int | float | str | tuple[float, ...] | list[VariableValue] | list[list[VariableValue]] | None
    ) = None


class ValueTable:
    """Codes and layouts of the value types, built from spec data."""

    def __init__(
        self, value_types: list[Any], codes: dict[str, int], prims: dict[str, Any], separator: int
    ) -> None:
        self.by_code: dict[int, Any] = {}
        self.by_name: dict[str, tuple[int, Any]] = {}
        self.separator = separator
        self.prims = prims
        for vt in value_types:
            self.by_code[codes[vt.name]] = vt
            self.by_name[vt.name] = (codes[vt.name], vt)

    @cache  # noqa: B019 - one table per process
    def _struct(self, fmt: str) -> struct.Struct:
        return struct.Struct(ORDER + fmt)

    def _prefix(self, name: str) -> struct.Struct:
        return self._struct(self.prims[name].struct)

    # --- decoding -----------------------------------------------------------

    def decode_all(self, buf: bytes, pos: int, end: int, field: str) -> list[VariableValue]:
        out = []
        while pos < end:
            value, pos = self._decode_one(buf, pos, end, field, 0)
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

    def _decode_one(
        self, buf: bytes, pos: int, end: int, field: str, depth: int
    ) -> tuple[VariableValue, int]:
        if depth > MAX_DEPTH:
            raise DecodeError(
                "global variable values nest too deeply",
                field=field,
                offset=pos,
                expected=f"<= {MAX_DEPTH} levels",
            )
        self._need(buf, pos, 1, end, field)
        code = buf[pos]
        vt = self.by_code.get(code)
        if vt is None:
            raise DecodeError(
                f"unknown global variable type {code}",
                field=field,
                offset=pos,
                expected=", ".join(f"{c} ({v.name})" for c, v in self.by_code.items()),
            )
        pos += 1
        if vt.kind == "none":
            return VariableValue(type=vt.name), pos
        if vt.kind == "scalar":
            prim = self.prims[vt.element]
            st = self._struct(prim.struct * vt.count)
            self._need(buf, pos, st.size, end, field)
            items = st.unpack_from(buf, pos)
            value = items[0] if vt.count == 1 else tuple(items)
            return VariableValue(type=vt.name, value=value), pos + st.size
        prefix = self._prefix(vt.length)
        self._need(buf, pos, prefix.size, end, field)
        (length,) = prefix.unpack_from(buf, pos)
        pos += prefix.size
        if vt.kind == "string":
            self._need(buf, pos, length, end, field)
            text = bytes(buf[pos : pos + length]).decode("utf-8", "surrogateescape")
            return VariableValue(type=vt.name, value=text), pos + length
        if vt.kind == "list":
            items_out = []
            for _ in range(length):
                item, pos = self._decode_one(buf, pos, end, field, depth + 1)
                items_out.append(item)
            return VariableValue(type=vt.name, value=items_out), pos
        # matrix: rows then columns, both of the length primitive
        self._need(buf, pos, prefix.size, end, field)
        (cols,) = prefix.unpack_from(buf, pos)
        pos += prefix.size
        rows = []
        for _ in range(length):
            row = []
            for _ in range(cols):
                item, pos = self._decode_one(buf, pos, end, field, depth + 1)
                row.append(item)
            rows.append(row)
        return VariableValue(type=vt.name, value=rows), pos

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
