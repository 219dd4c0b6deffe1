"""Primary/secondary interface fields with their availability, as `fields --primary` lists them.

A field's `since` (or its message's) is resolved per product line by the same rules
as RTDE fields, so "which firmware added this" has one answer for both interfaces.
"""

from __future__ import annotations

from dataclasses import dataclass

from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.schema import LayoutField
from rtde_spec.metamodel.versions import Version


@dataclass(frozen=True)
class PrimaryFieldInfo:
    message: str  # family/member
    name: str  # group.field for fields of a repeated or conditional group
    type: str
    doc: str | None
    since: dict[str, Version]


def _type(fld: LayoutField) -> str:
    if fld.kind == "value":
        return f"{fld.type}[{fld.count}]" if fld.count else fld.type
    if fld.kind == "string":
        return "string" if fld.length in (None, "rest") else f"string({fld.length})"
    return {"values": "variable_values"}.get(fld.kind, fld.kind)


def primary_fields(catalogue: Catalogue) -> list[PrimaryFieldInfo]:
    """Every field of every primary message member, groups flattened, in spec order."""
    out: list[PrimaryFieldInfo] = []

    def walk(fields: list[LayoutField], message: str, prefix: str, since: dict[str, str] | None) -> None:
        for fld in fields:
            own = fld.since or since
            if fld.fields is not None:
                walk(fld.fields, message, f"{prefix}{fld.name}.", own)
                continue
            resolved = catalogue.resolve_since(own)
            out.append(PrimaryFieldInfo(message, prefix + fld.name, _type(fld), fld.doc, resolved))

    for fam in catalogue.spec.primary.families:
        for member in fam.members:
            walk(member.fields, f"{fam.name}/{member.name}", "", member.since)
    return out


def available(info: PrimaryFieldInfo, catalogue: Catalogue, controller: str | Version) -> bool:
    version = Version.parse(controller)
    first = info.since.get(catalogue.line_of(version).id)
    return first is not None and version >= first
