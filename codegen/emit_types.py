"""Emit _generated/rtde_types.py: one pydantic-ready type per RTDE data type.

Bounds come from the primitive's size and sign; vectors are tuples of exactly
`count` elements, so a 5-element VECTOR6D fails validation, not the wire.
"""

from __future__ import annotations

from rtde_spec.metamodel.catalogue import Catalogue

from .render import PY_HEADER

PY_BY_KIND = {"int": "int", "float": "float", "bool": "bool"}


def scalar_annotation(kind: str, bounds: tuple[int, int] | None) -> str:
    if kind == "int" and bounds is not None:
        return f"Annotated[int, Field(ge={bounds[0]}, le={bounds[1]})]"
    return PY_BY_KIND[kind]


def emit_types(catalogue: Catalogue) -> str:
    out = [
        PY_HEADER,
        '"""Python types of the RTDE data types, with the wire\'s bounds."""\n\n',
        "from typing import Annotated, Any\n\n",
        "from pydantic import Field\n\n",
        "from rtde_spec.wire.model_types import AsciiStr\n\n",
    ]
    names: list[str] = []
    scalar_of: dict[str, str] = {}  # primitive -> name of the scalar type already emitted
    for wire in catalogue.wire_types.values():
        names.append(wire.name)
        if wire.kind == "str":
            out.append(f"{wire.name} = AsciiStr\n")
            continue
        element = scalar_of.get(wire.element or "") or scalar_annotation(wire.kind, wire.bounds)
        if wire.count == 1:
            out.append(f"{wire.name} = {element}\n")
            scalar_of.setdefault(wire.element or "", wire.name)
        else:
            out.append(f"{wire.name} = tuple[{', '.join([element] * wire.count)}]\n")
    out.append("\nWIRE_TYPES: dict[str, Any] = {\n")
    out += [f"    {name!r}: {name},\n" for name in names]
    out.append("}\n")
    return "".join(out)
