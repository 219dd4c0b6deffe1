"""Emit docs/reference/primary.md: every message and sub-package with a byte layout."""

from __future__ import annotations

from rtde_spec.spec.schema import CaseSpec, LayoutField, PackageField, Primitive, Spec

from .render import MD_HEADER, md_table


def _size(fld: LayoutField, prims: dict[str, Primitive]) -> int | None:
    kind = fld.kind
    if kind == "value":
        return prims[fld.type or ""].size * (fld.count or 1)
    if kind == "repeat" and isinstance(fld.repeat, int):
        inner = [_size(f, prims) for f in fld.fields or []]
        return None if None in inner else sum(i or 0 for i in inner) * fld.repeat
    return None


def _type_text(fld: LayoutField) -> str:
    kind = fld.kind
    if kind == "value":
        return f"{fld.type}[{fld.count}]" if fld.count else str(fld.type)
    if kind in ("string", "bytes"):
        length = "to end" if fld.length == "rest" else f"{fld.length} length, then bytes"
        fmt = ", newline-separated" if fld.format == "lines" else ""
        return f"{kind} ({length}{fmt})"
    if kind == "values":
        return "typed values (see below)"
    if kind == "switch":
        cases = []
        for value, case in (fld.cases or {}).items():
            text = f"{case.type} ({case.length} length)" if isinstance(case, CaseSpec) else case
            cases.append(f"{value}: {text}")
        return f"by {fld.switch}: " + ", ".join(cases)
    if kind == "optional":
        return f"{fld.group}, only when {fld.when}"
    times = "until the end" if fld.repeat == "until_end" else f"× {fld.repeat}"
    return f"{fld.group} {times}"


def _meaning(fld: LayoutField) -> str:
    text = fld.doc or ""
    if fld.enum:
        text += f" Values: [{fld.enum}](enums.md#{fld.enum.lower()})."
    if fld.unit:
        text += f" [{fld.unit}]"
    if fld.since:
        text += " Since " + ", ".join(f"{line} {v}" for line, v in fld.since.items()) + "."
    if fld.fallback:
        text += f" Without a length prefix that fits exactly, the text is the {fld.fallback}."
    if fld.peers:
        text += f" Peers: {fld.peers}"
    return text.strip()


def _rows(
    fields: list[LayoutField], prims: dict[str, Primitive], start: int | None, prefix: str = ""
) -> tuple[list[list[object]], int | None]:
    rows: list[list[object]] = []
    offset = start
    for fld in fields:
        size = _size(fld, prims)
        rows.append(
            [
                offset if offset is not None else "—",
                f"`{prefix}{fld.name}`",
                _type_text(fld),
                size if size is not None else "var",
                _meaning(fld),
            ]
        )
        if fld.fields is not None:
            inner, _ = _rows(fld.fields, prims, 0 if fld.kind == "repeat" else None, f"{prefix}{fld.name}.")
            for row in inner:
                row[0] = f"+{row[0]}" if row[0] != "—" else "—"
            rows += inner
        offset = offset + size if offset is not None and size is not None else None
    return rows, offset


def _header_rows(fields: list[PackageField], prims: dict[str, Primitive]) -> list[list[object]]:
    rows: list[list[object]] = []
    offset = 0
    for h in fields:
        meaning = (h.doc or "") + (f" Values: [{h.enum}](enums.md#{h.enum.lower()})." if h.enum else "")
        rows.append([offset, f"`{h.name}`", h.type, prims[h.type].size, meaning.strip()])
        offset += prims[h.type].size
    return rows


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
    out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], _header_rows(pf.header, prims))
    out += f"\nRobot State sub-package header ({shsize} bytes):\n\n"
    out += md_table(
        ["Offset", "Field", "Type", "Bytes", "Meaning"], _header_rows(pf.subpackage_header, prims)
    )
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
            rows, _ = _rows(fam.prefix, prims, 0)
            out += md_table(["Offset", "Field", "Type", "Bytes", "Meaning"], rows)
        prefix_size = sum(_size(f, prims) or 0 for f in fam.prefix)
        for m in fam.members:
            out += f"\n### {m.name} ({fam.name} sub-type {m.type})\n\n"
            if m.doc:
                out += f"{m.doc}\n\n"
            if m.since:
                out += "Since: " + ", ".join(f"{k} {v}" for k, v in m.since.items()) + "\n\n"
            for old in m.older:
                names = ", ".join(f"`{f.name}` ({f.type})" for f in old.fields)
                out += f"Controllers before {old.before} send an older layout (decoded when the Version "
                out += f"message names such a controller): {names}. Source: {old.source}.\n\n"
            rows, end = _rows(m.fields, prims, prefix_size)
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
    return out
