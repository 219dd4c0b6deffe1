"""The field catalogue: every concrete RTDE field with its type, size and availability.

Built from the generated spec data (no YAML is read at import). Register families
are expanded to concrete names, and `since` is resolved per product line, so
every question about "does this name exist on this controller" is answered here.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from rtde_spec.errors import RecipeError, UsageError
from rtde_spec.metamodel.versions import Version

if TYPE_CHECKING:
    from rtde_spec.metamodel.schema import FieldsFile, FieldSpec, Spec

Direction = Literal["input", "output"]
DIRECTIONS: tuple[Direction, ...] = ("input", "output")
EXTRA_FIELDS_ENV = "RTDE_SPEC_EXTRA_FIELDS"


@dataclass(frozen=True)
class WireTypeInfo:
    """An RTDE data type with everything a codec needs, derived from the spec."""

    name: str
    size: int | None  # None for STRING
    count: int
    element: str | None
    struct: str  # struct format for one value, e.g. "6d"; "" for STRING
    kind: str  # int | float | bool | str
    bounds: tuple[int, int] | None


@dataclass(frozen=True)
class LineInfo:
    """A product line (CB3, e-Series, PolyScope X) as the catalogue needs it."""

    id: str
    name: str
    majors: tuple[int, ...]
    first_version: str
    inherits: str | None
    rtde_max_frequency: int
    setup_names_max_bytes: int | None = None


@dataclass(frozen=True)
class FieldInfo:
    """One concrete field (register families expanded)."""

    name: str
    direction: Direction
    wire: WireTypeInfo
    doc: str | None
    unit: str | None
    enum: str | None
    bits: str | None
    deprecated: str | None
    reserved: str | None
    sources: tuple[str, ...]
    family: str | None
    index: int | None
    since: dict[str, Version] = field(default_factory=dict)  # product line id -> first version

    @property
    def type(self) -> str:
        return self.wire.name

    @property
    def size(self) -> int:
        return self.wire.size or 0


class Catalogue:
    """Fields, types and product lines of one spec (plus any extra fields files).

    The built-in catalogue is read from compiled tables (`_generated/catalogue_data`)
    without pydantic; the validated spec behind it is loaded only when asked for.
    """

    def __init__(self, spec: Spec, extra: Iterable[FieldsFile] = ()) -> None:
        self._spec: Spec | None = spec
        self.extra = tuple(extra)
        self.lines = {
            p.id: LineInfo(
                p.id,
                p.name,
                tuple(p.majors),
                p.first_version,
                p.inherits,
                p.rtde_max_frequency,
                p.rtde_setup_names_max_bytes,
            )
            for p in spec.product_lines.product_lines
        }
        self.wire_types = _wire_types(spec)
        self._fields: dict[Direction, dict[str, FieldInfo]] = {d: {} for d in DIRECTIONS}
        for fields_file in (spec.fields, *self.extra):
            pairs: tuple[tuple[Direction, list[FieldSpec]], ...] = (
                ("input", fields_file.inputs),
                ("output", fields_file.outputs),
            )
            for direction, entries in pairs:
                for entry in entries:
                    for info in self._expand(entry, direction):
                        self._fields[direction][info.name] = info

    @property
    def spec(self) -> Spec:
        """The validated meta-model (for the built-in catalogue: validated on first use)."""
        if self._spec is None:
            from rtde_spec._generated.spec_data import SPEC
            from rtde_spec.metamodel.schema import Spec

            self._spec = Spec.model_validate(SPEC)
        return self._spec

    # --- construction ---------------------------------------------------------

    @classmethod
    @cache
    def builtin(cls) -> Catalogue:
        """The catalogue compiled into this package (spec/ at codegen time)."""
        from rtde_spec._generated import catalogue_data as data

        self = cls.__new__(cls)
        self._spec = None
        self.extra = ()
        self.lines = {row[0]: LineInfo(*row) for row in data.LINES}
        self.wire_types = {row[0]: WireTypeInfo(*row) for row in data.WIRE_TYPES}
        self._fields = {d: {} for d in DIRECTIONS}
        parsed: dict[str, Version] = {}  # ~30 distinct versions among ~1,700 (start-up)
        for name, direction, wire, *middle, since in data.FIELDS:
            for v in since.values():
                if v not in parsed:
                    parsed[v] = Version.parse(v)
            versions = {line: parsed[v] for line, v in since.items()}
            fields: tuple[Any, ...] = (name, direction, self.wire_types[wire], *middle, versions)
            info = FieldInfo(*fields)
            self._fields[direction][name] = info
        return self

    def table_rows(self) -> dict[str, list[tuple[Any, ...]]]:
        """The catalogue as plain rows, which codegen writes to `_generated/catalogue_data`."""
        lines = [tuple(vars(line).values()) for line in self.lines.values()]
        wires = [tuple(vars(wire).values()) for wire in self.wire_types.values()]
        fields = []
        for info in self.fields():
            row = list(vars(info).values())
            row[2] = info.wire.name
            row[-1] = {line: str(v) for line, v in info.since.items()}
            fields.append(tuple(row))
        return {"LINES": lines, "WIRE_TYPES": wires, "FIELDS": fields}

    @classmethod
    def default(cls) -> Catalogue:
        """The built-in catalogue plus the files named in $RTDE_SPEC_EXTRA_FIELDS."""
        return _default_for(os.environ.get(EXTRA_FIELDS_ENV, ""))

    def with_extra(self, *paths: str | Path) -> Catalogue:
        """A new catalogue with the fields of extra YAML files (the shape of fields.yaml)."""
        from rtde_spec.metamodel.loader import load_fields_file
        from rtde_spec.metamodel.schema import FieldsFile

        extra = list(self.extra)
        for path in paths:
            merged = FieldsFile(
                inputs=[f for e in extra for f in e.inputs] + list(self.spec.fields.inputs),
                outputs=[f for e in extra for f in e.outputs] + list(self.spec.fields.outputs),
            )
            extra.append(load_fields_file(path, self.spec, against=merged))
        return Catalogue(self.spec, extra)

    def _expand(self, entry: FieldSpec, direction: Direction) -> list[FieldInfo]:
        wire = self.wire_types[entry.type]
        out = []
        for name, index in entry.concrete():
            rng = entry.range_for(index)
            since_map = rng.since if rng is not None and rng.since is not None else entry.since
            reserved = rng.reserved if rng is not None and rng.reserved else entry.reserved
            out.append(
                FieldInfo(
                    name=name,
                    direction=direction,
                    wire=wire,
                    doc=(entry.doc or "").replace("{X}", str(index)) or None,
                    unit=entry.unit,
                    enum=entry.enum,
                    bits=entry.bits,
                    deprecated=entry.deprecated,
                    reserved=reserved,
                    sources=tuple(entry.sources),
                    family=entry.name if entry.is_family else None,
                    index=index,
                    since=self._resolve_since(since_map),
                )
            )
        return out

    def resolve_since(self, since: dict[str, str] | None) -> dict[str, Version]:
        """Per product line the first version of a `since` map (omitted: every line; inherits)."""
        return self._resolve_since(since)

    def _resolve_since(self, since: dict[str, str] | None) -> dict[str, Version]:
        resolved: dict[str, Version] = {}
        for line in self.lines.values():
            if since is None:
                resolved[line.id] = Version.parse(line.first_version)
            elif line.id in since:
                resolved[line.id] = Version.parse(since[line.id])
            elif line.inherits is not None and line.inherits in since:
                resolved[line.id] = Version.parse(line.first_version)
        return resolved

    # --- questions ------------------------------------------------------------

    def setup_names_limit(self, version: str | Version | None) -> tuple[int | None, str]:
        """The documented byte limit of a setup's names on this version's line, and whose it is.

        Only the CB3 guide documents one (2048); other lines have none (None), and with no
        version the strictest documented limit applies, named as that line's.
        """
        if version is not None:
            line = self.line_of(version)
            return line.setup_names_max_bytes, line.name
        documented = [
            (p.setup_names_max_bytes, p.name) for p in self.lines.values() if p.setup_names_max_bytes
        ]
        return min(documented) if documented else (None, "")

    def line_of(self, version: str | Version) -> LineInfo:
        """The product line a controller version belongs to."""
        try:
            parsed = Version.parse(version)
        except ValueError as exc:
            raise RecipeError(str(exc), subject="controller version") from None
        for line in self.lines.values():
            if parsed.major in line.majors:
                return line
        known = ", ".join(f"{p.id} ({'/'.join(map(str, p.majors))}.x)" for p in self.lines.values())
        raise RecipeError(
            f"controller version {parsed} belongs to no known product line (known: {known})",
            subject="controller version",
        )

    def fields(
        self, direction: Direction | None = None, controller: str | Version | None = None
    ) -> list[FieldInfo]:
        """Fields in spec order, optionally of one direction and available on a controller."""
        directions = DIRECTIONS if direction is None else (direction,)
        out = [info for d in directions for info in self._of(d).values()]
        if controller is not None:
            out = [info for info in out if self.available(info, controller)]
        return out

    def get(self, name: str, direction: Direction) -> FieldInfo | None:
        try:
            return self._fields[direction].get(name)
        except KeyError:
            return self._of(direction).get(name)

    def names(self, direction: Direction) -> list[str]:
        return list(self._of(direction))

    def _of(self, direction: Direction) -> dict[str, FieldInfo]:
        """The fields of a direction; UsageError for one that is none ("outputs" was a KeyError)."""
        if direction not in self._fields:
            raise UsageError(f"direction must be {' or '.join(self._fields)}, not {direction!r}")
        return self._fields[direction]

    def available(self, info: FieldInfo, controller: str | Version) -> bool:
        """Whether a controller of this version knows the field."""
        version = Version.parse(controller)
        first = info.since.get(self.line_of(version).id)
        return first is not None and version >= first

    def since_text(self, info: FieldInfo) -> str:
        """ "cb3 3.4.0, e-series 5.0.0, polyscope-x 10.0.0" — or "not available"."""
        parts = [f"{line} {ver}" for line, ver in info.since.items()]
        return ", ".join(parts) if parts else "not available"


@cache
def _default_for(env_value: str) -> Catalogue:
    """One catalogue per value of the environment variable (files are read once)."""
    paths = [p for p in env_value.split(os.pathsep) if p]
    return Catalogue.builtin().with_extra(*paths) if paths else Catalogue.builtin()


def _wire_types(spec: Spec) -> dict[str, WireTypeInfo]:
    prims = {p.name: p for p in spec.primitives.primitives}
    out = {}
    for wire in spec.types.types:
        if wire.variable or wire.element is None:
            out[wire.name] = WireTypeInfo(wire.name, None, 1, None, "", "str", None)
            continue
        prim = prims[wire.element]
        struct = prim.struct if wire.count == 1 else f"{wire.count}{prim.struct}"
        out[wire.name] = WireTypeInfo(
            wire.name, prim.size * wire.count, wire.count, prim.name, struct, prim.kind, prim.bounds
        )
    return out
