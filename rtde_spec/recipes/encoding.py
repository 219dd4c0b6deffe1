"""Encoding data packages: one `struct` call on the happy path, a detailed check to explain a failure.

`struct` already refuses integers out of range and non-numbers, so a valid input
costs one generated flatten and one pack. What `struct` would let through (a
vector of the wrong length, a BOOL that is not 0/1) is checked inline; anything
that fails goes through the per-value checks, which either convert it (an
integral float for an integer) or raise EncodeError naming the field, the limit
and the value.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rtde_spec._generated.constants import BYTE_ORDER, DATA_PACKAGE_PREFIX_FORMAT, DATA_PACKAGE_TYPE
from rtde_spec.errors import EncodeError
from rtde_spec.spec.catalogue import FieldInfo, WireTypeInfo

PREFIX = struct.Struct(DATA_PACKAGE_PREFIX_FORMAT)


@dataclass(frozen=True)
class RecipeItem:
    """One variable of a recipe: its name, wire type, and byte offset in the payload."""

    name: str
    wire: WireTypeInfo
    offset: int
    info: FieldInfo | None = None


class _Refused(Exception):
    """The fast path saw something struct would accept but the recipe does not."""


def _is_bool(value: Any) -> bool:
    return value is True or value is False or (type(value) is int and value in (0, 1))


def _compile_flatten(items: Sequence[RecipeItem]) -> Callable[[Mapping[str, Any]], tuple[Any, ...]]:
    """A function from a dict of values to the flat tuple `struct` packs, written once per recipe."""
    lines = ["def flatten(v):"]
    parts = []
    for i, item in enumerate(items):
        lines.append(f"    x{i} = v[{item.name!r}]")
        if item.wire.count > 1:
            lines.append(f"    if len(x{i}) != {item.wire.count}: raise Refused")
            parts.append(f"*x{i}")
        else:
            parts.append(f"x{i}")
        if item.wire.kind == "bool":
            check = f"is_bool(x{i})" if item.wire.count == 1 else f"all(map(is_bool, x{i}))"
            lines.append(f"    if not {check}: raise Refused")
    lines.append(f"    return ({', '.join(parts)},)")
    scope: dict[str, Any] = {"Refused": _Refused, "is_bool": _is_bool}
    exec("\n".join(lines), scope)
    return scope["flatten"]  # type: ignore[no-any-return]


class Encoder:
    """Encodes one recipe's values into a payload or a whole data package."""

    def __init__(self, items: Sequence[RecipeItem], payload: struct.Struct, package_size: int) -> None:
        self.items = tuple(items)
        self.names = frozenset(i.name for i in items)
        self.payload_struct = payload
        self.package_struct = struct.Struct(PREFIX.format + payload.format[1:])
        self.package_size = package_size
        self._flatten = _compile_flatten(items)

    def payload(self, values: Any, strict: bool) -> bytes:
        if not strict and type(values) is dict and len(values) == len(self.names):
            try:
                return self.payload_struct.pack(*self._flatten(values))
            except (KeyError, TypeError, struct.error, _Refused):
                pass  # explained (or converted) below
        return self.payload_struct.pack(*self.checked(values, strict))

    def package(self, values: Any, recipe_id: int, strict: bool) -> bytes:
        if not strict and type(values) is dict and len(values) == len(self.names):
            try:
                flat = self._flatten(values)
                return self.package_struct.pack(self.package_size, DATA_PACKAGE_TYPE, recipe_id, *flat)
            except (KeyError, TypeError, struct.error, _Refused):
                pass
        try:
            prefix = PREFIX.pack(self.package_size, DATA_PACKAGE_TYPE, recipe_id)
        except (struct.error, TypeError):
            low, high = _bounds(PREFIX.format[-1])
            raise EncodeError(
                "recipe id out of range",
                package="data_package",
                field="recipe_id",
                expected=f"{low}..{high}",
                actual=recipe_id,
            ) from None
        return prefix + self.payload(values, strict)

    def checked(self, values: Any, strict: bool) -> list[Any]:
        """Every value checked against its wire type; the first problem raises, naming the field."""
        if hasattr(values, "model_dump"):  # a pydantic model (pydantic is imported only when used)
            values = values.model_dump()
        elif isinstance(values, tuple):
            if not hasattr(values, "_asdict"):
                raise EncodeError(
                    "a plain tuple has no field names; pass a record, dict or model", package="data_package"
                )
            values = values._asdict()
        if not isinstance(values, Mapping):
            raise EncodeError("values must be a dict, a record or a model", package="data_package")
        flat: list[Any] = []
        for item in self.items:
            if item.name not in values:
                raise EncodeError("missing value", package="data_package", field=item.name)
            value = values[item.name]
            if item.wire.count > 1:
                if not isinstance(value, (list, tuple)) or len(value) != item.wire.count:
                    raise EncodeError(
                        f"{item.wire.name} needs exactly {item.wire.count} values",
                        package="data_package",
                        field=item.name,
                        expected=f"{item.wire.count} values",
                        actual=repr(value),
                    )
                flat.extend(_checked(item, v, strict, i) for i, v in enumerate(value))
            else:
                flat.append(_checked(item, value, strict, None))
        extra = set(values) - self.names
        if extra:
            raise EncodeError(
                f"not in the recipe: {', '.join(sorted(extra))}",
                package="data_package",
                field=sorted(extra)[0],
            )
        return flat


def _bounds(code: str) -> tuple[int, int]:
    bits = 8 * struct.calcsize(BYTE_ORDER + code)
    return (0, (1 << bits) - 1) if code.isupper() else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)


def _checked(item: RecipeItem, value: Any, strict: bool, index: int | None) -> Any:
    wire = item.wire
    field = item.name if index is None else f"{item.name}[{index}]"

    def fail(reason: str, expected: Any) -> EncodeError:
        return EncodeError(reason, package="data_package", field=field, expected=expected, actual=repr(value))

    if wire.kind == "bool":
        if isinstance(value, bool):
            return value
        if not strict and isinstance(value, int) and value in (0, 1):
            return bool(value)
        raise fail("not a bool", "True or False" if strict else "a bool, 0 or 1")
    if wire.kind == "int":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise fail(f"not an integer for {wire.name}", wire.name)
        if isinstance(value, float):
            if strict or not value.is_integer():
                raise fail(f"not an integer for {wire.name}", wire.name)
            value = int(value)
        assert wire.bounds is not None
        low, high = wire.bounds
        if not low <= value <= high:
            raise fail(f"out of range for {wire.name}", f"{low}..{high}")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"not a number for {wire.name}", wire.name)
    return float(value)
