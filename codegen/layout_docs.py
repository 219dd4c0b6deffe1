"""The one reference-doc emitter of a layout: rows of offset, field, type, size and meaning.

RTDE packages (emit_docs) and primary messages (emit_primary_docs) are tables of
these rows; a field reads the same in both.
"""

from __future__ import annotations

from rtde_spec.metamodel.schema import CaseSpec, LayoutField, PackageField, Primitive


def field_size(fld: LayoutField, prims: dict[str, Primitive]) -> int | None:
    kind = fld.kind
    if kind == "value":
        return prims[fld.type or ""].size * (fld.count or 1)
    if kind == "repeat" and isinstance(fld.repeat, int):
        inner = [field_size(f, prims) for f in fld.fields or []]
        return None if None in inner else sum(i or 0 for i in inner) * fld.repeat
    return None


def _type_text(fld: LayoutField) -> str:
    kind = fld.kind
    if kind == "value":
        return f"{fld.type}[{fld.count}]" if fld.count else str(fld.type)
    if kind in ("string", "bytes"):
        length = "to end" if fld.length == "rest" else f"{fld.length} length, then bytes"
        fmt = {"lines": ", newline-separated", "csv": ", comma-separated"}.get(fld.format or "", "")
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
    if fld.source:
        text += ("" if text.rstrip().endswith(".") else ".") + f" Source: {fld.source}"
    if fld.fallback:
        text += f" Without a length prefix that fits exactly, the text is the {fld.fallback}."
    if fld.peers:
        text += f" Peers: {fld.peers}"
    return text.strip()


def layout_rows(
    fields: list[LayoutField], prims: dict[str, Primitive], start: int | None, prefix: str = ""
) -> tuple[list[list[object]], int | None]:
    """Offset, field, type, bytes, meaning of each field (groups' fields indented by name)."""
    rows: list[list[object]] = []
    offset = start
    for fld in fields:
        size = field_size(fld, prims)
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
            inner, _ = layout_rows(
                fld.fields, prims, 0 if fld.kind == "repeat" else None, f"{prefix}{fld.name}."
            )
            for row in inner:
                row[0] = f"+{row[0]}" if row[0] != "—" else "—"
            rows += inner
        offset = offset + size if offset is not None and size is not None else None
    return rows, offset


def header_rows(fields: list[PackageField], prims: dict[str, Primitive]) -> list[list[object]]:
    rows: list[list[object]] = []
    offset = 0
    for h in fields:
        meaning = (h.doc or "") + (f" Values: [{h.enum}](enums.md#{h.enum.lower()})." if h.enum else "")
        rows.append([offset, f"`{h.name}`", h.type, prims[h.type].size, meaning.strip()])
        offset += prims[h.type].size
    return rows
