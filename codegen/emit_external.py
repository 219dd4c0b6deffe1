"""Emit _generated/external_control.py and docs/reference/external-control.md from
spec/external_control/protocols.yaml (URCL's reverse, script sender, trajectory and
script command protocols). The Lua dissector for them is emitted by emit_lua_external.
"""

from __future__ import annotations

from rtde_spec.metamodel.external import Detect, ExternalControlFile, Variant
from rtde_spec.metamodel.schema import Primitive

from .render import GEN, MD_HEADER, literal_module, md_table


def emit_external(spec: ExternalControlFile, prims: dict[str, Primitive]) -> dict[str, str]:
    """Relative output path -> text for the external-control protocols of the loaded spec."""
    return {
        f"{GEN}/external_control.py": _python(spec),
        "docs/reference/external-control.md": _markdown(spec, prims),
    }


def _python(spec: ExternalControlFile) -> str:
    return literal_module(
        "External-control protocols (URCL) of spec/external_control/protocols.yaml.",
        "EXTERNAL_CONTROL",
        spec.model_dump(mode="json", exclude_defaults=True),
    )


def _variant_rows(variant: Variant, prims: dict[str, Primitive]) -> list[tuple[object, ...]]:
    rows: list[tuple[object, ...]] = []
    pos = 0
    for f in variant.fields:
        size = prims[f.type].size * (f.count or 1)
        kind = f.type if f.count is None else f"{f.type}[{f.count}]"
        scale = f"÷ {f.scale:.0f}" if f.scale else ""
        rows.append((pos, f"`{f.name}`", kind, scale, f.unit or "", f.enum or "", f.doc or ""))
        pos += size
    return rows


def _variant_head(selector: str | None, v: Variant) -> str:
    when = "default" if v.when is None else f"{selector} = {', '.join(map(str, v.when))}"
    return f"\n**{v.name}** ({when}; table `{v.table}`){': ' + v.doc if v.doc else ''}\n\n"


def _detect(detect: Detect | None) -> str:
    """How capture recognises a layout in the program the driver sent, as a sentence."""
    if detect is None:
        return "."
    lines = ", ".join(f"`{line}`" for line in detect.script_lines)
    sent = "the program sent to the script sender"
    without = ", ".join(f"`{line}`" for line in detect.without)
    absent = f" and not the lines {without}" if detect.without else ""
    anyvalue = ", ".join(f"`{name}`" for name in detect.any_multipliers)
    values = f"; {anyvalue} may hold any value" if detect.any_multipliers else ""
    return f". Capture picks it when {sent} has the lines {lines}{absent}{values} ({detect.source})."


def _choice_note(protocol: str, example: str) -> str:
    proto = f"urcl_{protocol}"
    return (
        "\nA program names a layout when it has all of the layout's lines, none of its `without` "
        "lines, and sets no multiplier (`MULT_...`) they do not name but those that may hold any "
        "value; capture uses a layout when the program names it and no other. "
        "Without such a program in the capture, `rtde-spec capture` keeps the layouts the records "
        "themselves allow (segments of whole records of its size, every enum word a known value): "
        "one left is taken, else the newest of them; its summary names the layout and why.\n"
        "\nThe Wireshark dissector (`rtde-spec wireshark`) chooses the same way from a program it "
        "has seen earlier in the capture (else the newest), or as its preference "
        f"`{proto}.layout` says (`-o {proto}.layout:{example}`); each record "
        f"shows `{proto}.layout` and `{proto}.layout_reason`, and an older "
        f"layout's fields are `{proto}.<layout>.<field>`.\n"
    )


def _markdown(spec: ExternalControlFile, prims: dict[str, Primitive]) -> str:
    out = [
        MD_HEADER,
        "# External control (UR's client library)\n\n",
        f"The protocols between {spec.library} (the core of UR's ROS drivers) and the URScript\n",
        "program it runs on the robot. The driver's PC listens on each port; the robot connects.\n",
        f"Words are {spec.byte_order}-endian int32; a scaled value is sent multiplied by its scale\n",
        f"(the table's `÷`), decoded in SI units. Source: {spec.doc_ref}.\n",
    ]
    headers = ["offset", "field", "type", "scale", "unit", "enum", "meaning"]
    for p in spec.protocols:
        out.append(f"\n## {p.name} (port {p.port})\n\n{p.doc or ''}\n\nSource: {p.source}.\n")
        if p.request is not None:
            out.append(f"\nThe robot sends `{p.request.strip()}` and a newline; rows go to `{p.table}`.\n")
        for m in p.messages:
            out.append(f"\n### {m.name}: {m.sender} → {'robot' if m.sender == 'driver' else 'driver'}, ")
            out.append(f"{m.record_bytes} bytes\n")
            if m.layout is not None:
                out.append(f"\nThe newest layout, `{m.layout}`{_detect(m.detect)}\n")
            for v in m.variants:
                out.append(_variant_head(m.selector, v))
                out.append(md_table(headers, _variant_rows(v, prims)))
            for old in m.older:
                out.append(f"\n**older layout {old.name}** ({old.record_bytes} bytes): {old.source}")
                out.append(f"{_detect(old.detect)}\n")
                for v in old.variants:
                    out.append(_variant_head(old.selector, v) if len(old.variants) > 1 else "\n")
                    out.append(md_table(headers, _variant_rows(v, prims)))
            if m.older:
                out.append(_choice_note(p.name, m.older[-1].name))
    out.append("\n## Enums\n")
    for e in spec.enums:
        out.append(f"\n### {e.name}\n\n{e.doc or ''}{' (' + e.doc_ref + ')' if e.doc_ref else ''}\n\n")
        out.append(md_table(["value", "name", "meaning"], [(v.value, v.name, v.doc or "") for v in e.values]))
    return "".join(out)
