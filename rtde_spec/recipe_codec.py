"""Data packages of one recipe, compiled once to a struct.Struct from the spec's types.

The hot path (500 Hz live, millions of packages from captures) does one
`unpack_from` per package and slices vectors out of the flat tuple; nothing is
looked up per package.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from .catalogue import Catalogue, Direction, FieldInfo, WireTypeInfo
from .errors import DecodeError, EncodeError, RecipeError


@dataclass(frozen=True)
class RecipeItem:
    """One variable of a recipe: its name, wire type, and byte offset in the payload."""

    name: str
    wire: WireTypeInfo
    offset: int
    info: FieldInfo | None = None


class RecipeCodec:
    """Decode and encode the payload of data packages for one ordered list of variables."""

    def __init__(self, items: Sequence[tuple[str, WireTypeInfo, FieldInfo | None]]) -> None:
        if not items:
            raise RecipeError("a recipe needs at least one variable")
        layout: list[RecipeItem] = []
        offset = 0
        fmt = ">"
        for name, wire, info in items:
            if wire.size is None:
                raise RecipeError(f"type {wire.name} cannot be in a data package", field=name)
            layout.append(RecipeItem(name, wire, offset, info))
            offset += wire.size
            fmt += wire.struct
        self.items = tuple(layout)
        self.names = tuple(item.name for item in layout)
        self.struct = struct.Struct(fmt)
        self.size = self.struct.size
        # (name, start, stop) into the flat unpacked tuple; stop None = scalar
        spans = []
        pos = 0
        for item in layout:
            count = item.wire.count
            spans.append((item.name, pos, pos + count if count > 1 else None))
            pos += count
        self._spans = tuple(spans)

    @classmethod
    def for_names(
        cls, names: Sequence[str], direction: Direction, catalogue: Catalogue | None = None
    ) -> RecipeCodec:
        """A codec for variable names, typed from the spec's catalogue."""
        cat = catalogue or Catalogue.default()
        items = []
        for name in names:
            info = cat.get(name, direction)
            if info is None:
                raise RecipeError(f"unknown {direction} field {name!r}", field=name)
            items.append((name, info.wire, info))
        return cls(items)

    @classmethod
    def for_types(
        cls, names: Sequence[str], types: Sequence[str], catalogue: Catalogue | None = None
    ) -> RecipeCodec:
        """A codec from a setup request's names and the reply's type names."""
        cat = catalogue or Catalogue.default()
        if len(names) != len(types):
            raise RecipeError(
                "setup reply lists a different number of types than names were requested",
                expected=len(names),
                actual=len(types),
            )
        items = []
        for name, type_name in zip(names, types, strict=True):
            wire = cat.wire_types.get(type_name)
            if wire is None:
                raise RecipeError(f"type {type_name!r} has no data layout", field=name)
            items.append((name, wire, None))
        return cls(items)

    def decode(self, payload: bytes | bytearray | memoryview, *, offset: int = 0) -> dict[str, Any]:
        """Values by name; vectors as tuples. `offset` is where the payload starts in `payload`."""
        if len(payload) - offset != self.size:
            raise self._size_error(len(payload) - offset)
        flat = self.struct.unpack_from(payload, offset)
        return {
            name: flat[start] if stop is None else flat[start:stop]
            for name, start, stop in self._spans
        }

    def _size_error(self, got: int) -> DecodeError:
        short = got < self.size
        where = None
        if short:
            where = next(item for item in self.items if item.offset + (item.wire.size or 0) > got)
        return DecodeError(
            "data package payload is shorter than its recipe"
            if short
            else "data package payload is longer than its recipe",
            package="data_package",
            field=where.name if where else None,
            offset=4 + (where.offset if where else self.size),
            expected=f"{self.size} payload bytes",
            actual=f"{got} payload bytes",
        )

    def encode(self, values: Mapping[str, Any]) -> bytes:
        """The payload for a value per variable; EncodeError names a missing or bad field."""
        flat: list[Any] = []
        for item in self.items:
            if item.name not in values:
                raise EncodeError("missing value", package="data_package", field=item.name)
            value = values[item.name]
            if item.wire.count > 1:
                if not isinstance(value, (list, tuple)) or len(value) != item.wire.count:
                    raise EncodeError(
                        f"{item.wire.name} needs {item.wire.count} values",
                        package="data_package",
                        field=item.name,
                        expected=f"{item.wire.count} values",
                        actual=repr(value),
                    )
                for element in value:
                    flat.append(_checked(item, element))
            else:
                flat.append(_checked(item, value))
        return self.struct.pack(*flat)


def _checked(item: RecipeItem, value: Any) -> Any:
    wire = item.wire
    if wire.kind == "bool":
        if not isinstance(value, (bool, int)):
            raise EncodeError(
                "not a bool",
                package="data_package",
                field=item.name,
                expected="bool",
                actual=repr(value),
            )
        return bool(value)
    if wire.kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise EncodeError(
                "not an integer",
                package="data_package",
                field=item.name,
                expected=wire.name,
                actual=repr(value),
            )
        assert wire.bounds is not None
        low, high = wire.bounds
        if not low <= value <= high:
            raise EncodeError(
                f"out of range for {wire.name}",
                package="data_package",
                field=item.name,
                expected=f"{low}..{high}",
                actual=value,
            )
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise EncodeError(
            "not a number",
            package="data_package",
            field=item.name,
            expected=wire.name,
            actual=repr(value),
        )
    return float(value)
