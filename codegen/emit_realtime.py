"""Emit _generated/realtime.py and docs/reference/realtime.md from spec/realtime/interface.yaml.

The real-time message is one fixed run of doubles per version, so each version's layout
compiles here to one struct format (a plan per product line and first version); the
runtime decoder picks a plan by version and unpacks with one `struct.Struct` call.
"""

from __future__ import annotations

from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.realtime import LayoutPlan, RealtimeFile, layouts

from .render import GEN, MD_HEADER, literal_module, md_table


def emit_realtime(table: RealtimeFile, catalogue: Catalogue) -> dict[str, str]:
    """Relative output path -> text, for the real-time interface of the loaded spec."""
    plans = layouts(table, catalogue)
    return {
        f"{GEN}/realtime.py": _python(table, plans),
        "docs/reference/realtime.md": _markdown(table, plans),
    }


def _python(table: RealtimeFile, plans: list[LayoutPlan]) -> str:
    rows = []
    for p in plans:
        names = tuple(f.name for f in p.fields)
        counts = tuple(f.count or 1 for f in p.fields)
        integers = tuple(f.name for f in p.fields if f.integer)
        rows.append(f"    ({p.line!r}, {p.first!r}, {p.size}, {p.format!r},\n     {names!r},\n")
        rows.append(f"     {counts!r},\n     {integers!r}),\n")
    prelude = (
        f"REALTIME_PORTS: dict[str, int] = {dict(table.ports)!r}\n"
        + f"REALTIME_MAX_MESSAGE_BYTES = {table.max_message_bytes}\n"
        + "# (product line, first version, message size, struct format, field names, value counts,\n"
        + "#  fields carrying a whole number in a double)\n"
        + "LAYOUTS: tuple[tuple[Any, ...], ...] = (\n"
        + "".join(rows)
        + ")\n\n"
    )
    return literal_module(
        "The real-time interface (port 30003) of spec/realtime/interface.yaml and its layouts.",
        "REALTIME",
        table.model_dump(mode="json", exclude_defaults=True),
        prelude,
    )


def _markdown(table: RealtimeFile, plans: list[LayoutPlan]) -> str:
    ports = ", ".join(f"{k} {v}" for k, v in table.ports.items())
    out = [
        MD_HEADER,
        "# Real-time interface\n\n",
        f"Ports: {ports}. One message per control step (125 Hz on CB3, 500 Hz on e-Series): a\n",
        "big-endian int32 message size (this field included), then the fields below, every value\n",
        "a big-endian double. Newer versions append fields; a version sends those whose `since`\n",
        f"it has reached. Source: {table.doc_ref}; the other sources are named in the spec file.\n\n",
        "## Message size per version\n\n",
        md_table(["product line", "from version", "bytes"], [(p.line, p.first, p.size) for p in plans]),
        "\n## Fields\n\n",
    ]
    rows = []
    offset = 4
    for f in table.fields:
        since = ", ".join(f"{k} {v}" for k, v in (f.since or {}).items()) or "every version"
        count = f.count or 1
        kind = "int in a double" if f.integer else f.type
        extra = f" (values: {f.enum})" if f.enum else ""
        rows.append((f"`{f.name}`", offset, count, kind, f.unit or "", f"`{f.rtde}`" if f.rtde else "", since,
                     (f.doc or "") + extra))  # fmt: skip
        offset += 8 * count
    out.append(
        md_table(["field", "offset", "values", "type", "unit", "RTDE output", "since", "meaning"], rows)
    )
    peers = [(f"`{f.name}`", f.peers) for f in table.fields if f.peers]
    if peers:
        out.append("\n## How other implementations read it\n\n")
        out.append(md_table(["field", "decision"], peers))
    return "".join(out)
