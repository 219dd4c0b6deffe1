"""The real-time message's layout for one controller version: compiled once, from the spec.

Codegen compiled every version's field list to one struct format (`_generated/realtime.py`);
here a version (or, with none, a message size) picks its plan. Decoding a message is
one `struct.Struct.unpack_from` and a regrouping of the flat doubles into the fields.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from typing import Any

from rtde_spec._generated.constants import PRODUCT_LINES
from rtde_spec._generated.realtime import LAYOUTS, REALTIME_MAX_MESSAGE_BYTES
from rtde_spec.errors import DecodeError, EncodeError, UsageError
from rtde_spec.metamodel.versions import Version

HEADER = struct.Struct(">i")
PACKAGE = "realtime message"


@dataclass(frozen=True)
class RealtimeLayout:
    """The fields one controller version sends on port 30003, in order, and their struct plan."""

    line: str
    first: str  # the first version of its product line with exactly these fields
    size: int  # bytes of the whole message, size field included
    names: tuple[str, ...]
    counts: tuple[int, ...]
    integers: frozenset[str]
    plan: struct.Struct = field(repr=False, compare=False)

    def offset(self, name: str) -> int:
        """Byte offset of a field in the message (the size field is at 0)."""
        at = HEADER.size
        for n, count in zip(self.names, self.counts, strict=True):
            if n == name:
                return at
            at += 8 * count
        raise KeyError(name)

    def decode(self, data: bytes | bytearray | memoryview, at: int = 0) -> dict[str, Any]:
        """The fields of the message starting at byte `at` (its size already checked)."""
        flat = self.plan.unpack_from(data, at)
        out: dict[str, Any] = {"message_size": flat[0]}
        i = 1
        integers = self.integers
        for name, count in zip(self.names, self.counts, strict=True):
            if count == 1:
                value: Any = flat[i]
                if name in integers:
                    value = _whole(value, name, self, at)
            else:
                value = flat[i : i + count]
                if name in integers:
                    value = tuple(_whole(v, name, self, at) for v in value)
            out[name] = value
            i += count
        return out

    def encode(self, values: Mapping[str, Any]) -> bytes:
        """One message of this layout; a field not given, or only sent by other versions, is sent
        as zeros. A name of no version, a value that is no number (or no whole number where the
        field is a mode or bits) is an EncodeError naming the field: a misspelt name was dropped,
        text was taken as a number, 1.5 made a message the decoder refuses."""
        unknown = sorted(set(values) - _field_names())
        if unknown:
            raise EncodeError(
                f"not a field of any real-time layout: {', '.join(unknown)}",
                package=PACKAGE,
                field=unknown[0],
            )
        flat: list[float] = [float(self.size)]
        for name, count in zip(self.names, self.counts, strict=True):
            value = values.get(name)
            if value is None:
                flat.extend((0.0,) * count)
                continue
            try:
                parts = [value] if count == 1 or isinstance(value, (str, bytes)) else list(value)
                if any(isinstance(v, (str, bytes)) for v in parts):
                    raise TypeError("text is no number")
                items = [float(v) for v in parts]
            except (TypeError, ValueError, OverflowError) as exc:
                raise EncodeError(
                    f"not {'a number' if count == 1 else f'{count} numbers'} ({exc})",
                    package=PACKAGE, field=name, actual=repr(value)[:80],
                ) from None  # fmt: skip
            if len(items) != count:
                raise EncodeError(
                    "wrong number of values", package=PACKAGE, field=name, expected=count, actual=len(items)
                )
            if name in self.integers and not all(math.isfinite(v) and v == int(v) for v in items):
                raise EncodeError(
                    "not a whole number", package=PACKAGE, field=name, expected="a whole number",
                    actual=repr(value)[:80],
                )  # fmt: skip
            flat.extend(items)
        return self.plan.pack(int(flat[0]), *flat[1:])


def _whole(value: float, name: str, layout: RealtimeLayout, at: int) -> int:
    """A mode or bit field carried in a double, as the int it is."""
    if not math.isfinite(value) or value != int(value):
        raise DecodeError(
            "not a whole number", package=PACKAGE, field=name, offset=at + layout.offset(name),
            expected="a whole number in a double", actual=value,
        )  # fmt: skip
    return int(value)


def _line_of(version: Version) -> str:
    for line, majors in PRODUCT_LINES.items():
        if version.major in majors:
            return line
    raise UsageError(f"controller version {version} belongs to no product line", subject="controller version")


@cache
def _all() -> tuple[RealtimeLayout, ...]:
    return tuple(
        RealtimeLayout(line, first, size, names, counts, frozenset(integers), struct.Struct(fmt))
        for line, first, size, fmt, names, counts, integers in LAYOUTS
    )


@cache
def _field_names() -> frozenset[str]:
    return frozenset(name for plan in _all() for name in plan.names) | {"message_size"}


@cache
def layout_for(version: str | Version) -> RealtimeLayout:
    """The layout a controller of `version` sends (UsageError for a version of no product line)."""
    try:
        parsed = Version.parse(version)
    except ValueError as exc:
        raise UsageError(str(exc), subject="controller version") from None
    line = _line_of(parsed)
    found = [p for p in _all() if p.line == line and Version.parse(p.first) <= parsed]
    if not found:
        first = min((p.first for p in _all() if p.line == line), key=Version.parse)
        raise UsageError(
            f"version {parsed} is older than {first}, the spec's first real-time layout of {line}"
        )
    return found[-1]


def layout_for_size(size: int) -> RealtimeLayout | None:
    """With no version known: the layout whose message is exactly `size` bytes, if one is."""
    for plan in _all():
        if plan.size == size:
            return plan  # equal sizes on two lines carry the same fields (the spec only appends)
    return None


@cache
def all_columns() -> dict[str, str]:
    """Every layout's columns as tables hold them (vectors as name_0..name_N), in order, each
    with its numpy type: one column set for every version, so files of controllers of several
    versions read as one table. A column some version does not send is nullable ("f8?"): null
    in that version's files; the rest are never null (Parquet stores them faster)."""
    plans = sorted(_all(), key=lambda p: p.size)
    code = plans[0].plan.format.lstrip("<>!=@")[0]  # the size field, as the struct plan reads it
    size = f"{'i' if code.islower() else 'u'}{struct.calcsize('=' + code)}"
    columns: dict[str, str] = {"message_size": size}
    sets = []
    for plan in plans:
        names = []
        for name, count in zip(plan.names, plan.counts, strict=True):
            kind = "i8" if name in plan.integers else "f8"
            for flat in [name] if count == 1 else [f"{name}_{i}" for i in range(count)]:
                if columns.setdefault(flat, kind) != kind:
                    raise AssertionError(f"real-time field {flat} changes type between layouts")
                names.append(flat)
        sets.append(set(names))
    everywhere = set.intersection(*sets)
    return {n: t if n in everywhere or n == "message_size" else t + "?" for n, t in columns.items()}


def known_sizes() -> tuple[int, ...]:
    return tuple(sorted({p.size for p in _all()}))


def check_size(size: int, available: int | None = None, at: int = 0) -> None:
    """Refuse a size field no real-time message can have, before anything is buffered."""
    if size < HEADER.size + 8 or size > REALTIME_MAX_MESSAGE_BYTES:
        raise DecodeError(
            "impossible message size", package=PACKAGE, field="message_size", offset=at,
            expected=f"12..{REALTIME_MAX_MESSAGE_BYTES}", actual=size,
        )  # fmt: skip
    if available is not None and available < size:
        raise DecodeError(
            "message cut short", package=PACKAGE, offset=at, expected=f"{size} bytes", actual=available
        )
