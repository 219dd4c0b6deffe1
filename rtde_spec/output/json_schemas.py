"""JSON Schemas of the messages MCAP files and the live view carry, generated from the spec.

Foxglove reads a channel's JSON Schema to offer its fields in plots and panels, so
every field the spec knows is typed from it: RTDE recipe variables from the
catalogue's wire types (a VECTOR6D is an array of exactly 6 numbers), RTDE packages
and primary/secondary messages from their layouts (groups become objects, repeats
arrays). What no layout describes (a row's offset, capture time, connection) is
typed from its value. NaN and infinities are written as null: JSON has no such
numbers, and the schema's description says so.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import cache
from typing import Any

from rtde_spec._generated.spec_data import SPEC
from rtde_spec.metamodel.catalogue import Catalogue, FieldInfo, WireTypeInfo

NAN_NOTE = "NaN and infinities are null (JSON has no such numbers)."
_JSON_TYPES = {"bool": "boolean", "int": "integer", "float": "number"}


@cache
def _primitives() -> dict[str, dict[str, Any]]:
    return {p["name"]: p for p in SPEC["primitives"]["primitives"]}


def primitive(name: str) -> dict[str, Any]:
    """The schema of one spec primitive (`uint8`, `double`, ...): type and, for integers, bounds."""
    prim = _primitives().get(name)
    if prim is None:
        return {}
    out: dict[str, Any] = {"type": _JSON_TYPES.get(prim["kind"], "string")}
    if prim["kind"] == "int":
        bits = 8 * prim["size"]
        low, high = (
            (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if prim.get("signed") else (0, (1 << bits) - 1)
        )
        out.update(minimum=low, maximum=high)
    return out


def wire_type(wire: WireTypeInfo) -> dict[str, Any]:
    """The schema of an RTDE data type: a vector is an array of exactly `count` elements."""
    one = primitive(wire.element) if wire.element else {"type": "string"}
    if wire.count == 1:
        return one
    return {"type": "array", "items": one, "minItems": wire.count, "maxItems": wire.count}


def recipe_field(info: FieldInfo) -> dict[str, Any]:
    """A recipe variable: its wire type's schema with the catalogue's doc and unit."""
    return _described(wire_type(info.wire), info.doc, info.unit)


def _described(schema: dict[str, Any], doc: str | None, unit: str | None) -> dict[str, Any]:
    text = " ".join(t for t in (doc, f"[{unit}]" if unit else None) if t)
    return {**schema, "description": text} if text else schema


def spec_field(field: Mapping[str, Any]) -> dict[str, Any]:
    """One field of a package layout in the spec: primitives, counts, strings, bytes, groups."""
    schema: dict[str, Any]
    if "fields" in field:  # a group: an object, repeated as an array
        group: dict[str, Any] = {"type": "object", "properties": layout(field["fields"])}
        repeat = field.get("repeat")
        if repeat is None:
            schema = group
        elif isinstance(repeat, int):
            schema = {"type": "array", "items": group, "minItems": repeat, "maxItems": repeat}
        else:
            schema = {"type": "array", "items": group}
    elif "switch" in field:  # the value's type depends on another field: one of the cases
        cases = [c if isinstance(c, Mapping) else {"type": c} for c in field["cases"].values()]
        schema = {"anyOf": _unique([spec_field(c) for c in cases])}
    elif field.get("type") == "string":
        schema = {"type": "string"}
    elif field.get("type") == "bytes":
        schema = {"type": "string", "contentEncoding": "base16"}
    else:
        schema = primitive(str(field.get("type")))
        count = field.get("count")
        if schema and isinstance(count, int):
            schema = {"type": "array", "items": schema, "minItems": count, "maxItems": count}
    return _described(schema, field.get("doc"), field.get("unit")) if schema else {}


def layout(fields: list[Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """Properties of every field of a spec layout, by name."""
    return {f["name"]: spec_field(f) for f in fields}


def _unique(schemas: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    for s in schemas:
        if s not in out:
            out.append(s)
    return out


@cache
def rtde_package(name: str) -> dict[str, dict[str, Any]]:
    """Properties of an RTDE package (`text_message`, `setup_outputs_v2`, ...) from its layout."""
    for message in SPEC["packages"]["messages"]:
        if message["name"] == name:
            return layout(message.get("fields", []))
    return {}


@cache
def rtde_package_names() -> frozenset[str]:
    return frozenset(m["name"] for m in SPEC["packages"]["messages"])


@cache
def primary_part(name: str) -> dict[str, dict[str, Any]]:
    """Properties of a primary/secondary message or Robot State sub-package from its layout
    (a tagged family's shared prefix, such as its timestamp, included)."""
    for family in SPEC["primary"]["families"]:
        if family["name"] == name:
            return layout(family.get("fields", []))
        for member in family.get("members", []):
            if member["name"] == name:
                return {**layout(family.get("prefix") or []), **layout(member.get("fields", []))}
    return {}


@cache
def primary_part_names() -> frozenset[str]:
    """Names of every primary/secondary message family and member."""
    families = SPEC["primary"]["families"]
    return frozenset(
        [f["name"] for f in families] + [m["name"] for f in families for m in f.get("members", [])]
    )


def inferred(value: Any) -> dict[str, Any]:
    """A schema from a value, for what no layout describes."""
    if isinstance(value, bool):
        return {"type": "boolean"}
    if isinstance(value, int):
        return {"type": "integer"}
    if isinstance(value, float):
        return {"type": "number"}
    if isinstance(value, str):
        return {"type": "string"}
    if isinstance(value, Mapping):
        return {"type": "object", "properties": {str(k): inferred(v) for k, v in value.items()}}
    if isinstance(value, (list, tuple)):
        return {"type": "array", "items": inferred(value[0]) if value else {}}
    return {}


def _json_type(schema: Mapping[str, Any]) -> str | None:
    return schema.get("type") if isinstance(schema.get("type"), str) else None


def _fits(schema: Mapping[str, Any], value: Any) -> bool:
    """Whether a value is of the schema's JSON type (null stands for NaN in number fields)."""
    kind = _json_type(schema)
    if kind is None or value is None:
        return True
    return kind == _json_type(inferred(value)) or (
        kind == "number" and _json_type(inferred(value)) == "integer"
    )


def object_schema(
    title: str, message: Mapping[str, Any], known: Mapping[str, dict[str, Any]]
) -> dict[str, Any]:
    """The schema of messages shaped like `message`: spec-typed where `known` has the field
    (and the value agrees with it), typed from the value elsewhere."""
    properties = {}
    for name, value in message.items():
        spec = known.get(name)
        properties[name] = spec if spec and _fits(spec, value) else inferred(value)
    return {"title": title, "description": NAN_NOTE, "type": "object", "properties": properties}


def recipe_fields(
    names: list[str] | tuple[str, ...], catalogue: Catalogue | None = None
) -> dict[str, dict[str, Any]]:
    """Properties of the recipe variables among `names` (either direction), from the catalogue."""
    cat = catalogue or Catalogue.default()
    out = {}
    for name in names:
        info = cat.get(name, "output") or cat.get(name, "input")
        if info is not None:
            out[name] = recipe_field(info)
    return out


def finite(value: Any) -> Any:
    """The value with NaN and infinities as None, for encoders that would write them as bare NaN."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    return value
