"""Emit _generated/enums.py: IntEnum value tables and IntFlag bit layouts with docs."""

from __future__ import annotations

from rtde_spec.metamodel.schema import Spec

from .render import PY_HEADER, docstring


def _class_doc(doc: str | None, doc_ref: str | None) -> str:
    text = doc or ""
    if doc_ref:
        text += f"\n\nSource: {doc_ref}"
    return text


def emit_enums(spec: Spec) -> str:
    out = [
        PY_HEADER,
        '"""Value tables and bit layouts of the spec; `VALUE_DOCS` holds per-value docs."""\n\n',
        "from enum import IntEnum, IntFlag\n",
    ]
    docs: dict[str, dict[int, str]] = {}
    for enum in spec.all_enums:
        out.append(f"\n\nclass {enum.name}(IntEnum):\n")
        out.append(docstring(_class_doc(enum.doc, enum.doc_ref)))
        out.append("\n")
        for value in enum.values:
            out.append(f"    {value.name} = {value.value}\n")
            if value.doc:
                out.append(docstring(value.doc))
                docs.setdefault(enum.name, {})[value.value] = value.doc
    for bitfield in spec.all_bitfields:
        out.append(f"\n\nclass {bitfield.name}(IntFlag):\n")
        out.append(docstring(_class_doc(bitfield.doc, bitfield.doc_ref)))
        out.append("\n")
        for bit in bitfield.bits:
            out.append(f"    {bit.name} = 1 << {bit.bit}\n")
            if bit.doc:
                out.append(docstring(bit.doc))
                docs.setdefault(bitfield.name, {})[1 << bit.bit] = bit.doc
    out.append("\n\nENUMS: dict[str, type[IntEnum]] = {\n")
    out += [f"    {e.name!r}: {e.name},\n" for e in spec.all_enums]
    out.append("}\n\nBITFIELDS: dict[str, type[IntFlag]] = {\n")
    out += [f"    {b.name!r}: {b.name},\n" for b in spec.all_bitfields]
    out.append("}\n\nVALUE_DOCS: dict[str, dict[int, str]] = {\n")
    for name, values in docs.items():
        out.append(f"    {name!r}: {{\n")
        out += [f"        {value}: {text!r},\n" for value, text in values.items()]
        out.append("    },\n")
    out.append("}\n")
    return "".join(out)
