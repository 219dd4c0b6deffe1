"""Emit docs/reference/*.md: fields, packages with byte layouts, enums, types."""

from __future__ import annotations

from itertools import groupby

from rtde_spec.metamodel.catalogue import Catalogue, FieldInfo
from rtde_spec.metamodel.schema import FieldSpec, MessageSpec, Spec

from .conflict_docs import conflict_rows, conflicts_section
from .layout_docs import header_rows, layout_rows
from .render import MD_HEADER, md_table


def _since_cell(infos: list[FieldInfo], catalogue: Catalogue) -> str:
    """'3.4.0 / 5.0.0 / 10.0.0' per line; families grouped by equal availability."""

    def one(info: FieldInfo) -> str:
        return " / ".join(str(info.since.get(line, "—")) for line in catalogue.lines)

    if len(infos) == 1:
        return one(infos[0])
    parts = []
    for text, group in groupby(infos, key=one):
        members = list(group)
        parts.append(f"[{members[0].index}..{members[-1].index}] {text}")
    return "; ".join(parts)


def _sentence(text: str | None) -> str:
    """Prose that ends like a sentence, so appended notes read apart from it."""
    text = (text or "").strip()
    return text if not text or text[-1] in ".)]?!" else text + "."


def _meaning(entry: FieldSpec, infos: list[FieldInfo]) -> str:
    text = _sentence(entry.doc)
    if entry.enum:
        text += f" Values: [{entry.enum}](enums.md#{entry.enum.lower()})."
    if entry.bits:
        text += f" Bits: [{entry.bits}](enums.md#{entry.bits.lower()})."
    reserved = sorted({(i.index, i.reserved) for i in infos if i.reserved}, key=lambda x: x[0] or 0)
    if reserved and entry.is_family:
        idx = [r[0] for r in reserved]
        text += f" [{idx[0]}..{idx[-1]}] reserved for {reserved[0][1]}."
    elif reserved:
        text += f" Reserved for {reserved[0][1]}."
    if entry.deprecated:
        text += f" Deprecated: {entry.deprecated}."
    if entry.doc_ref:
        text += f" ({entry.doc_ref})"
    return text.strip()


def _fields_section(title: str, direction: str, entries: list[FieldSpec], cat: Catalogue) -> str:
    rows = []
    index_lines = []
    for entry in entries:
        names = [n for n, _ in entry.concrete()]
        infos = [cat.get(n, direction) for n in names]  # type: ignore[arg-type]
        infos_ok = [i for i in infos if i is not None]
        wire = cat.wire_types[entry.type]
        name = (
            f"`{entry.name}` (X = {entry.index[0]}..{entry.index[1]})" if entry.index else f"`{entry.name}`"
        )
        rows.append(
            [
                name,
                entry.type,
                wire.size if wire.size is not None else "var",
                _since_cell(infos_ok, cat),
                entry.unit or "",
                _meaning(entry, infos_ok),
                ", ".join(entry.sources),
            ]
        )
        if entry.is_family:
            index_lines.append(f"- `{entry.name}`: " + ", ".join(f"`{n}`" for n in names))
    lines = " / ".join(cat.lines)
    out = f"## {title}\n\n"
    out += md_table(["Name", "Type", "Bytes", f"Since ({lines})", "Unit", "Meaning", "Listed in"], rows)
    if index_lines:
        out += "\nConcrete names of the register families:\n\n" + "\n".join(index_lines) + "\n"
    return out


def emit_fields_doc(spec: Spec, cat: Catalogue) -> str:
    n_in, n_out = len(cat.fields("input")), len(cat.fields("output"))
    lines_rows = [
        [
            p.id,
            p.name,
            ", ".join(f"{m}.x" for m in p.majors),
            p.first_version,
            p.inherits or "",
            p.rtde_max_frequency,
        ]
        for p in spec.product_lines.product_lines
    ]
    out = MD_HEADER + "\n# RTDE fields\n\n"
    out += (
        f"{n_in} input and {n_out} output fields ({len(spec.fields.inputs)} and "
        f"{len(spec.fields.outputs)} entries; register families expanded). "
        "Inputs are written by the client, outputs sent by the controller; the register "
        "read-backs (`input_*_register*` among the outputs) are outputs too.\n\n"
        "**Since** gives the first version per product line; `—` means the line does not "
        "have the field. A line that `inherits` has every field of its parent line unless "
        "the field names the line itself.\n\n"
    )
    out += md_table(
        ["Line", "Name", "Versions", "First RTDE version", "Inherits", "Max frequency (Hz)"],
        lines_rows,
    )
    out += "\n" + _fields_section("Inputs (client → controller)", "input", spec.fields.inputs, cat)
    out += "\n" + _fields_section("Outputs (controller → client)", "output", spec.fields.outputs, cat)
    entries = [*spec.fields.inputs, *spec.fields.outputs]
    out += conflicts_section([row for e in entries for row in conflict_rows(e.name, e.conflicts)])
    return out


def _layout_rows(msg: MessageSpec, spec: Spec) -> list[list[object]]:
    prims = {p.name: p for p in spec.primitives.primitives}
    head = header_rows(spec.packages.header, prims)
    body, _ = layout_rows(msg.fields, prims, sum(prims[h.type].size for h in spec.packages.header))
    return head + body


def emit_packages_doc(spec: Spec) -> str:
    pk = spec.packages
    names = {p.code: p.name for p in pk.package_types}
    out = MD_HEADER + "\n# RTDE packages\n\n"
    out += (
        f"Port {pk.port}. Big-endian. Every package starts with the header; `size` counts "
        "the whole package, header included.\n\n"
    )
    out += md_table(["Type", "Code", "Name"], [[p.code, ord(p.code), p.name] for p in pk.package_types])
    out += "\nLimits: " + ", ".join(f"{k} = {v}" for k, v in pk.limits.model_dump().items()) + "\n"
    out += "\nSenders: " + "; ".join(f"**{k}** = {v}" for k, v in pk.senders.items()) + "\n"
    rows = [[m.name, m.type, " and ".join(m.senders), ", ".join(map(str, m.protocols))] for m in pk.messages]
    out += "\n## Layouts\n\n" + md_table(["Message", "Type", "From", "Protocol"], rows)
    for msg in pk.messages:
        out += f"\n### {msg.name}\n\n"
        out += f"{names[msg.type]} (`{msg.type}`) from {' and '.join(msg.senders)}, "
        out += f"protocol {', '.join(map(str, msg.protocols))}. {msg.doc or ''}\n\n"
        out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], _layout_rows(msg, spec))
    return out + _recipe_id_section(spec)


def _recipe_id_section(spec: Spec) -> str:
    """Which data packages carry the recipe id byte, with each rule's sources."""
    rules = spec.packages.data_recipe_id
    if not rules:
        return ""
    out = (
        "\n## The recipe id in data packages\n\n"
        "Where it is optional, a decoder tells the two forms apart by the package's size against "
        "its recipe's (they differ by the one byte); a package without the id belongs to the "
        "implied recipe. Encoders write the id; the emulator sends each form as a real sender "
        "does (Sent).\n\n"
    )
    rows = [
        [
            ", ".join(map(str, r.protocols)),
            " and ".join(r.senders),
            r.recipe_id,
            "—" if r.implied is None else r.implied,
            r.sent or "with",
            " ".join((r.doc or "").split()),
        ]
        for r in rules
    ]
    out += md_table(["Protocol", "From", "Recipe id", "Implied id", "Sent", "Why"], rows)
    for r in rules:
        out += f"\nSources (protocol {', '.join(map(str, r.protocols))}, {' and '.join(r.senders)}):\n\n"
        out += "".join(f"- {source}\n" for source in r.sources)
    return out


def emit_enums_doc(spec: Spec) -> str:
    users: dict[str, list[str]] = {}
    for direction in ("inputs", "outputs"):
        for entry in getattr(spec.fields, direction):
            for ref in (entry.enum, entry.bits):
                if ref:
                    users.setdefault(ref, []).append(f"`{entry.name}`")
    for msg in spec.packages.messages:
        for fld in msg.fields:
            if fld.enum:
                users.setdefault(fld.enum, []).append(f"`{msg.name}.{fld.name}`")
    out = MD_HEADER + "\n# Enums and bit layouts\n\nShared by RTDE and the primary/secondary interfaces.\n"
    for enum in spec.all_enums:
        out += f"\n## {enum.name}\n\n{enum.doc or ''}\n"
        if enum.doc_ref:
            out += f"\nSource: {enum.doc_ref}\n"
        if enum.name in users:
            out += f"\nUsed by: {', '.join(sorted(set(users[enum.name])))}\n"
        out += "\n" + md_table(
            ["Name", "Value", "Meaning"], [[v.name, v.value, v.doc or ""] for v in enum.values]
        )
    for bitfield in spec.all_bitfields:
        out += f"\n## {bitfield.name}\n\n{bitfield.doc or ''}\n"
        if bitfield.name in users:
            out += f"\nUsed by: {', '.join(sorted(set(users[bitfield.name])))}\n"
        rows = [[b.bit, b.name, f"0x{1 << b.bit:X}", b.doc or ""] for b in bitfield.bits]
        out += "\n" + md_table(["Bit", "Name", "Mask", "Meaning"], rows)
    return out


def emit_types_doc(spec: Spec, cat: Catalogue) -> str:
    rows = []
    for wire in spec.types.types:
        info = cat.wire_types[wire.name]
        rng = f"{info.bounds[0]}..{info.bounds[1]}" if info.bounds else ""
        rows.append(
            [
                wire.name,
                wire.element or "char",
                wire.count if not wire.variable else "n",
                info.size if info.size is not None else "n",
                f"`>{info.struct}`" if info.struct else "",
                rng,
                wire.doc or "",
            ]
        )
    prim_rows = [
        [p.name, p.size, f"`{p.struct}`", p.kind, "yes" if p.signed else "", p.doc or ""]
        for p in spec.primitives.primitives
    ]
    out = MD_HEADER + "\n# RTDE data types\n\nAll values are big-endian (network byte order).\n\n"
    out += md_table(["Type", "Element", "Count", "Bytes", "struct", "Range", "Meaning"], rows)
    out += "\nSetup replies may hold, in place of a type: "
    out += "; ".join(f"`{a.name}` — {a.doc}" for a in spec.types.setup_answers) + "\n"
    out += "\n## Primitives\n\n" + md_table(
        ["Name", "Bytes", "struct", "Kind", "Signed", "Meaning"], prim_rows
    )
    return out


def emit_index_doc(spec: Spec, cat: Catalogue) -> str:
    out = MD_HEADER + "\n# Reference\n\nGenerated from `spec/`; regenerate with `python -m codegen`.\n\n"
    out += f"- [RTDE fields](rtde-fields.md): {len(cat.fields('input'))} inputs, "
    out += f"{len(cat.fields('output'))} outputs\n"
    out += f"- [RTDE packages](rtde-packages.md): {len(spec.packages.package_types)} package types, "
    out += f"{len(spec.packages.messages)} layouts\n"
    out += f"- [Enums and bit layouts](enums.md): {len(spec.all_enums)} enums, "
    out += f"{len(spec.all_bitfields)} bit layouts\n"
    out += f"- [RTDE data types](rtde-types.md): {len(spec.types.types)} types\n"
    members = sum(len(f.members) for f in spec.primary.families)
    out += f"- [Primary and secondary interfaces](primary.md): {len(spec.primary.families)} message "
    out += f"families, {members} sub-packages and sub-messages\n"
    out += "- [Real-time interface](realtime.md): port 30003 (30013 read-only), layouts per version\n"
    out += "- [Dashboard server](dashboard.md): port 29999, commands and reply texts\n"
    out += "- [External control (UR's client library)](external-control.md): ports 50001-50004, the\n"
    out += "  reverse, script sender, trajectory point and script command protocols\n"
    out += "- [Arm models](arms.md): DH parameters and limits per arm\n"
    return out
