"""The primary interface as the codec reads it: plain dataclasses from the generated spec data.

The meta-model (`spec.schema`) validates spec/primary when codegen runs; `_generated/spec_data`
holds the result as dicts (its dump: defaults left out). The codec needs a few facts of
each family, member and value type, so it reads them from those dicts, and a client,
a capture or a decode of the primary interface starts without building the meta-model.
Attribute names are the meta-model's (`FamilySpec`, `MemberSpec`, `ValueTypeSpec`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rtde_spec.wire.fields import WireField, WirePrimitive, wire_fields, wire_primitives


@dataclass(frozen=True)
class OlderView:
    before: str  # the first version that sends the current layout instead
    source: str
    fields: tuple[WireField, ...]


@dataclass(frozen=True)
class MemberView:
    name: str
    type: int
    fields: tuple[WireField, ...]
    older: tuple[OlderView, ...] = ()
    since: Mapping[str, str] | None = None


@dataclass(frozen=True)
class FamilyView:
    name: str
    type: int
    layout: str  # subpackages | tagged | opaque
    tag: str | None
    prefix: tuple[WireField, ...]
    members: tuple[MemberView, ...]


@dataclass(frozen=True)
class ValueTypeView:
    name: str
    kind: str  # none | string | scalar | list | matrix
    element: str | None
    count: int
    length: str | None


@dataclass(frozen=True)
class PrimaryView:
    """spec/primary/interface.yaml with the primitives and enum codes it refers to."""

    primitives: dict[str, WirePrimitive]
    codes: dict[str, dict[str, int]]  # enum name -> value name -> value, RTDE and primary enums
    header: tuple[WireField, ...]
    subpackage_header: tuple[WireField, ...]
    max_message_bytes: int
    value_separator: int
    value_types: tuple[ValueTypeView, ...]
    families: tuple[FamilyView, ...]


def primary_view(spec: Mapping[str, Any]) -> PrimaryView:
    """The view of a spec's data: `_generated.spec_data.SPEC`, or `Spec.model_dump(mode="json",
    exclude_defaults=True)` of a validated spec (the same shape)."""
    pf = spec["primary"]
    enums = [*spec.get("enums", {}).get("enums", []), *spec.get("primary_enums", {}).get("enums", [])]
    return PrimaryView(
        primitives=wire_primitives(spec["primitives"]["primitives"]),
        codes={e["name"]: {v["name"]: int(v["value"]) for v in e["values"]} for e in enums},
        header=wire_fields(pf["header"]),
        subpackage_header=wire_fields(pf["subpackage_header"]),
        max_message_bytes=int(pf["max_message_bytes"]),
        value_separator=int(pf["value_separator"]),
        value_types=tuple(
            ValueTypeView(v["name"], v["kind"], v.get("element"), int(v.get("count", 1)), v.get("length"))
            for v in pf["value_types"]
        ),
        families=tuple(_family(f) for f in pf["families"]),
    )


def _family(data: Mapping[str, Any]) -> FamilyView:
    members = tuple(
        MemberView(
            m["name"],
            int(m["type"]),
            wire_fields(m["fields"]),
            tuple(OlderView(o["before"], o["source"], wire_fields(o["fields"])) for o in m.get("older", [])),
            m.get("since"),
        )
        for m in data.get("members", [])
    )
    return FamilyView(
        data["name"],
        int(data["type"]),
        data["layout"],
        data.get("tag"),
        wire_fields(data.get("prefix", [])),
        members,
    )
