"""The layout engine's view of spec fields: plain frozen dataclasses read from generated data.

The meta-model (`spec.schema`, pydantic) validates spec/ when codegen runs and writes
it to `_generated/spec_data.py` as plain dicts. Decoding needs only a few facts of
each field, so the runtime builds these from those dicts without pydantic: a capture
or a client starts without building the ~40 meta-model classes. `Layout` takes these
or the meta-model's own `LayoutField`/`Primitive` (the shapes below say what it reads).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from rtde_spec.wire.kinds import field_kind, int_bounds


class CaseLike(Protocol):
    """A switch case that is a length-prefixed text (the meta-model's `CaseSpec`)."""

    @property
    def type(self) -> str: ...
    @property
    def length(self) -> str | None: ...


class FieldLike(Protocol):
    """What the engine reads of a layout field (the meta-model's `LayoutField`, or `WireField`)."""

    @property
    def name(self) -> str: ...
    @property
    def type(self) -> str: ...
    @property
    def count(self) -> int | None: ...
    @property
    def length(self) -> str | None: ...
    @property
    def fallback(self) -> str | None: ...
    @property
    def format(self) -> str | None: ...
    @property
    def repeat(self) -> int | str | None: ...
    @property
    def when(self) -> str | None: ...
    @property
    def switch(self) -> str | None: ...
    @property
    def cases(self) -> Mapping[int, str | CaseLike] | None: ...
    @property
    def fields(self) -> Sequence[FieldLike] | None: ...
    @property
    def enum(self) -> str | None: ...
    @property
    def scale(self) -> float | None: ...
    @property
    def group(self) -> str | None: ...
    @property
    def kind(self) -> str: ...


class PrimitiveLike(Protocol):
    """What the engine reads of a primitive (the meta-model's `Primitive`, or `WirePrimitive`)."""

    @property
    def name(self) -> str: ...
    @property
    def size(self) -> int: ...
    @property
    def struct(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def signed(self) -> bool | None: ...
    @property
    def bounds(self) -> tuple[int, int] | None: ...


@dataclass(frozen=True, slots=True)
class WireCase:
    type: str
    length: str | None = None


@dataclass(frozen=True, slots=True)
class WireField:
    """One layout field as the engine needs it; `kind` as the meta-model's `LayoutField.kind`."""

    name: str
    type: str = ""
    count: int | None = None
    length: str | None = None
    fallback: str | None = None
    format: str | None = None
    repeat: int | str | None = None
    when: str | None = None
    switch: str | None = None
    cases: Mapping[int, str | WireCase] | None = None
    group: str | None = None  # the generated model class of a group's entries
    fields: tuple[WireField, ...] | None = None
    enum: str | None = None
    unit: str | None = None
    scale: float | None = None
    since: Mapping[str, str] | None = None

    @property
    def kind(self) -> str:
        """value | string | bytes | values | repeat | optional | switch."""
        return field_kind(self.type, self.fields is not None, self.when, self.switch)


@dataclass(frozen=True, slots=True)
class WirePrimitive:
    name: str
    size: int
    struct: str
    kind: str
    signed: bool | None = None

    @property
    def bounds(self) -> tuple[int, int] | None:
        """Inclusive integer range, derived from size and signedness (as `Primitive.bounds`)."""
        return int_bounds(self.kind, self.size, self.signed)


def wire_field(data: Mapping[str, Any]) -> WireField:
    """A field from its generated dict (the meta-model's dump: defaults left out, JSON keys)."""
    cases = data.get("cases")
    inner = data.get("fields")
    return WireField(
        name=data["name"],
        type=data.get("type", ""),
        count=data.get("count"),
        length=data.get("length"),
        fallback=data.get("fallback"),
        format=data.get("format"),
        repeat=data.get("repeat"),
        when=data.get("when"),
        switch=data.get("switch"),
        cases=None if cases is None else {int(k): _case(v) for k, v in cases.items()},
        group=data.get("group"),
        fields=None if inner is None else wire_fields(inner),
        enum=data.get("enum"),
        unit=data.get("unit"),
        scale=None if data.get("scale") is None else float(data["scale"]),
        since=data.get("since"),
    )


def wire_fields(items: Sequence[Mapping[str, Any]]) -> tuple[WireField, ...]:
    return tuple(wire_field(f) for f in items)


def wire_primitives(items: Sequence[Mapping[str, Any]]) -> dict[str, WirePrimitive]:
    """name -> primitive, from the generated `primitives` list."""
    return {
        p["name"]: WirePrimitive(p["name"], int(p["size"]), p["struct"], p["kind"], p.get("signed"))
        for p in items
    }


def _case(value: str | Mapping[str, Any]) -> str | WireCase:
    return value if isinstance(value, str) else WireCase(value["type"], value.get("length"))
