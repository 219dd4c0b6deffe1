"""Emit the primary-interface layer: pydantic models (and their registry) and
construct structs, one per sub-package / tagged message, from spec/primary/."""

from __future__ import annotations

from typing import Any

from rtde_spec.metamodel.schema import FamilySpec, LayoutField, MemberSpec, Primitive, Spec

from .emit_construct import CONSTRUCT_BY_STRUCT, prims_of, struct_body
from .model_fields import field_lines
from .render import PY_HEADER, camel, docstring, upper


def _groups(fields: list[LayoutField], out: list[tuple[str, list[LayoutField], str | None]]) -> None:
    for fld in fields:
        if fld.fields is not None:
            _groups(fld.fields, out)  # inner groups first: they are referenced
            out.append((fld.group or "", fld.fields, fld.doc))


def _member_class(
    family: str, prefix: list[LayoutField], tag: str | None, member: MemberSpec, prims: dict[str, Primitive]
) -> str:
    doc = member.doc or member.name.replace("_", " ")
    doc += f"\n\n{family} sub-type {member.type}."
    if member.since:
        doc += " Since " + ", ".join(f"{k} {v}" for k, v in member.since.items()) + "."
    out = [f"\n\nclass {camel(member.name)}(PrimaryPart):\n", docstring(doc), "\n"]
    out.append(f"    NAME: ClassVar[str] = {member.name!r}\n")
    out.append(f"    FAMILY: ClassVar[str] = {family!r}\n")
    out.append(f"    TYPE: ClassVar[int] = {member.type}\n")
    enums = {f.name: f.enum for f in [*prefix, *member.fields] if f.enum}
    out.append(f"    ENUMS: ClassVar[dict[str, str]] = {enums!r}\n\n")
    defaults = {tag: member.type} if tag else {}
    out += field_lines([*prefix, *member.fields], prims, optional=True, defaults=defaults)
    return "".join(out)


def emit_primary_models(spec: Spec) -> str:
    prims = prims_of(spec)
    pf = spec.primary
    out = [
        PY_HEADER,
        '"""pydantic models of the primary/secondary interface, and the codec\'s lookup tables.\n\n'
        "Every field of a sub-package or message may be None: older firmware sends fewer\n"
        "fields (listed in `missing`), newer firmware more (kept in `extra`).\n"
        '"""\n\n',
        "from typing import Annotated, ClassVar\n\n",
        "from pydantic import Field\n\n",
        "from rtde_spec.wire.model_types import WireText\n",
        "from rtde_spec.wire.primary_base import PrimaryGroup, PrimaryPart\n",
        "from rtde_spec.wire.primary_values import VariableValue\n\n",
        f"PORTS: dict[str, int] = {dict(pf.ports)!r}\n",
        f"MAX_MESSAGE_BYTES = {pf.max_message_bytes}\n",
        f"FAMILY_TYPES: dict[str, int] = { ({f.name: f.type for f in pf.families})!r}\n",
    ]
    groups: list[tuple[str, list[LayoutField], str | None]] = []
    for fam in pf.families:
        _groups(fam.prefix, groups)
        for member in fam.members:
            _groups(member.fields, groups)
    for name, fields, doc in groups:
        out.append(f"\n\nclass {name}(PrimaryGroup):\n")
        out.append(docstring(doc or name))
        out.append(f"\n    NAME: ClassVar[str] = {name!r}\n")
        enums = {f.name: f.enum for f in fields if f.enum}
        out.append(f"    ENUMS: ClassVar[dict[str, str]] = {enums!r}\n\n")
        out += field_lines(fields, prims, optional=False)
    registry = []
    for fam in pf.families:
        for member in fam.members:
            out.append(_member_class(fam.name, fam.prefix, fam.tag, member, prims))
            registry.append(f"    ({fam.name!r}, {member.type}): {camel(member.name)},\n")
    out.append("\n\nMEMBERS: dict[tuple[str, int], type[PrimaryPart]] = {\n")
    out += registry
    out.append("}\n\nGROUPS: dict[str, type[PrimaryGroup]] = {\n")
    out += [f"    {name!r}: {name},\n" for name, _, _ in groups]
    out.append("}\n")
    if "VariableValue" not in "".join(out[10:]):
        out = [o.replace("from rtde_spec.wire.primary_values import VariableValue\n", "") for o in out]
    return "".join(out)


# --- construct ---------------------------------------------------------------


def emit_primary_structs(spec: Spec) -> str:
    prims = prims_of(spec)
    pf = spec.primary
    header = struct_body([LayoutField(name=h.name, type=h.type) for h in pf.header], prims, "    ")
    sub = struct_body([LayoutField(name=h.name, type=h.type) for h in pf.subpackage_header], prims, "    ")
    out = [
        PY_HEADER,
        '"""construct structs of the primary interface: one per sub-package or tagged message.\n\n'
        "`<FAMILY>_<MEMBER>` parses the body after the sub-package header (Robot State)\n"
        "or after the message header (tagged messages, prefix included). A readable\n"
        "definition: rtde_spec.primary.codec decodes with compiled structs instead.\n"
        '"""\n\n',
        "# ruff: noqa: F401\n",
        "from construct import (\n",
    ]
    names = [
        "Array",
        "Const",
        "FixedSized",
        "GreedyBytes",
        "GreedyRange",
        "GreedyString",
        "If",
        "PascalString",
        "Peek",
        "Prefixed",
        "Struct",
        "Switch",
        "this",
        *sorted(set(CONSTRUCT_BY_STRUCT.values())),
    ]
    out += [f"    {n},\n" for n in names]
    out.append(")\n\nfrom rtde_spec.wire.construct_ext import lines_string, prefixed_or_rest\n")
    out.append(f"\nMESSAGE_HEADER = Struct(\n{header})\n")
    out.append(f"\nSUBPACKAGE_HEADER = Struct(\n{sub})\n")
    for fam in pf.families:
        for member in fam.members:
            body = struct_body([*fam.prefix, *member.fields], prims, "    ")
            out.append(f"\n{upper(fam.name)}_{upper(member.name)} = Struct(\n{body})\n")
    out += [_whole_message(fam, pf.header, pf.subpackage_header, prims) for fam in pf.families]
    return "".join(out)


def _whole_message(
    fam: FamilySpec, header: list[Any], sub_header: list[Any], prims: dict[str, Primitive]
) -> str:
    """`<FAMILY>_MESSAGE`: a whole message, header included; members chosen by their type number."""
    c = CONSTRUCT_BY_STRUCT
    size_c, type_c = (c[prims[h.type].struct] for h in header)
    head = f"{sum(prims[h.type].size for h in header)}"
    name = upper(fam.name)
    if fam.layout == "opaque":
        body = "GreedyBytes"
    elif fam.layout == "subpackages":
        sub_size_c, sub_type_c = (c[prims[h.type].struct] for h in sub_header)
        sub_head = sum(prims[h.type].size for h in sub_header)
        cases = ", ".join(f"{m.type}: {name}_{upper(m.name)}" for m in fam.members)
        switch = f"Switch(this.type, {{{cases}}}, default=GreedyBytes)"
        body = (
            f'GreedyRange(Struct("size" / {sub_size_c}, "type" / {sub_type_c}, '
            f'"body" / FixedSized(this.size - {sub_head}, {switch})))'
        )
    else:
        prefix = struct_body(fam.prefix, prims, "            ")
        cases = ", ".join(f"{m.type}: {name}_{upper(m.name)}" for m in fam.members)
        body = (
            f'Struct(\n        "prefix" / Peek(Struct(\n{prefix}        )),\n'
            f'        "member" / Switch(this.prefix.{fam.tag}, {{{cases}}}, default=GreedyBytes),\n    )'
        )
    return (
        f"\n{name}_MESSAGE = Struct(\n"
        f'    "size" / {size_c},\n'
        f'    "type" / Const({fam.type}, {type_c}),\n'
        f'    "body" / FixedSized(this.size - {head}, {body}),\n'
        ")\n"
    )
