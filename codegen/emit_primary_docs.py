"""Emit docs/reference/primary.md: every message and sub-package with a byte layout."""

from __future__ import annotations

from rtde_spec.metamodel.schema import Spec

from .conflict_docs import conflict_rows, conflicts_section
from .layout_docs import field_size, header_rows, layout_rows
from .render import MD_HEADER, md_table


def emit_primary_doc(spec: Spec) -> str:
    pf = spec.primary
    prims = {p.name: p for p in spec.primitives.primitives}
    hsize = sum(prims[h.type].size for h in pf.header)
    shsize = sum(prims[h.type].size for h in pf.subpackage_header)
    out = MD_HEADER + "\n# Primary and secondary interfaces\n\n"
    out += "Ports: " + ", ".join(f"{k} {v}" for k, v in pf.ports.items()) + ". Big-endian.\n\n"
    out += (
        "Compatibility rule: newer firmware may append fields. A part longer than its layout "
        "decodes the known fields and keeps the rest as `extra` bytes; a shorter one decodes "
        "the fields present and lists the others in `missing`; unknown message, sub-package "
        "and sub-message types are kept with their bytes. Offsets below count from the start "
        "of the body (after the header); `—` means the offset depends on earlier data.\n\n"
    )
    out += f"Message header ({hsize} bytes); a size above {pf.max_message_bytes} is refused:\n\n"
    out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], header_rows(pf.header, prims))
    out += f"\nRobot State sub-package header ({shsize} bytes):\n\n"
    out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], header_rows(pf.subpackage_header, prims))
    summary = []
    for fam in pf.families:
        for m in fam.members:
            summary.append([fam.name, fam.type, m.name, m.type])
        if not fam.members:
            summary.append([fam.name, fam.type, "(opaque)", ""])
    out += "\n## Messages\n\n" + md_table(["Family", "Message type", "Member", "Sub-type"], summary)
    for fam in pf.families:
        out += f"\n## {fam.name} (type {fam.type})\n\n{fam.doc or ''}\n"
        if fam.prefix:
            out += f"\nEvery {fam.name} starts with these fields; `{fam.tag}` selects the member:\n\n"
            rows, _ = layout_rows(fam.prefix, prims, 0)
            out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], rows)
        prefix_size = sum(field_size(f, prims) or 0 for f in fam.prefix)
        for m in fam.members:
            out += f"\n### {m.name} ({fam.name} sub-type {m.type})\n\n"
            if m.doc:
                out += f"{m.doc}\n\n"
            if m.source:
                out += f"Sources: {m.source}\n\n"
            if m.since:
                out += "Since: " + ", ".join(f"{k} {v}" for k, v in m.since.items()) + "\n\n"
            for old in m.older:
                names = ", ".join(f"`{f.name}` ({f.type})" for f in old.fields)
                out += f"Controllers before {old.before} send an older layout (decoded when the Version "
                out += f"message names such a controller): {names}. Source: {old.source}.\n\n"
            rows, end = layout_rows(m.fields, prims, prefix_size)
            out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], rows)
            if end is not None and fam.layout == "subpackages":
                out += f"\nLayout size: {end} bytes (sub-package size {end + shsize}).\n"
    out += "\n## Global variable values\n\n"
    out += (
        "Each top-level value is a type byte, its data, and the separator byte "
        f"0x{pf.value_separator:02x}; LIST and MATRIX elements are (type, value) pairs without "
        "separators. Type codes: [GlobalVariableType](enums.md#globalvariabletype). The "
        "document's worked example shows BOOL with code 0x0c, which its own table gives to "
        "POSE; the spec follows the table (BOOL = 13).\n\n"
    )
    vrows = [
        [v.name, v.kind, f"{v.element} × {v.count}" if v.element else "", v.length or ""]
        for v in pf.value_types
    ]
    out += md_table(["Type", "Kind", "Data", "Length prefix"], vrows)
    rows = []
    for fam in pf.families:
        for m in fam.members:
            rows += conflict_rows(m.name, m.conflicts)
            rows += [r for f in m.fields for r in conflict_rows(f"{m.name}.{f.name}", f.conflicts)]
    out += conflicts_section(rows)
    return out
