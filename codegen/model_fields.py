"""The one pydantic emitter of layout fields: their Python types and annotated lines.

RTDE package models (emit_rtde) and primary message models (emit_primary) are
classes of these lines; only text differs (RTDE: ASCII with the wire's length bound).
"""

from __future__ import annotations

from rtde_spec.metamodel.schema import CaseSpec, LayoutField, Primitive

from .emit_types import scalar_annotation
from .render import field_description


def _case_annotation(case: str | CaseSpec, prims: dict[str, Primitive]) -> str:
    if isinstance(case, CaseSpec):
        return "WireText"
    prim = prims[case]
    return {"int": "int", "float": "float", "bool": "bool"}[prim.kind]


def annotation_of(fld: LayoutField, prims: dict[str, Primitive], text: str = "utf8") -> str:
    """The Python type of one field; `text="ascii"` for RTDE, whose text is ASCII and bounded."""
    kind = fld.kind
    if kind == "value":
        prim = prims[fld.type or ""]
        one = scalar_annotation(prim.kind, prim.bounds)
        if fld.count:
            return f"Annotated[tuple[{one}, ...], Field(min_length={fld.count}, max_length={fld.count})]"
        return one
    if kind == "string" and text == "ascii":
        if fld.format == "csv":
            return "Annotated[list[CsvItem], Field(min_length=1)]"
        return "ShortAsciiStr" if fld.length == "uint8" else "AsciiStr"
    if kind == "string":
        return "list[WireText]" if fld.format else "WireText"
    if kind == "bytes":
        return "bytes"
    if kind == "values":
        return "list[VariableValue]"
    if kind == "switch":
        options = sorted(
            {_case_annotation(c, prims) for c in (fld.cases or {}).values()},
            key=lambda a: "str" if a == "WireText" else a,  # float, int, str: as with the builtin name
        )
        return " | ".join(options)
    if kind == "optional":
        return f"{fld.group}"
    if isinstance(fld.repeat, int):
        return f"Annotated[tuple[{fld.group}, ...], Field(min_length={fld.repeat}, max_length={fld.repeat})]"
    return f"list[{fld.group}]"


def field_lines(
    fields: list[LayoutField],
    prims: dict[str, Primitive],
    optional: bool,
    defaults: dict[str, int] | None = None,
    text: str = "utf8",
) -> list[str]:
    """Annotated pydantic field lines with their docs; `optional` ones default to None."""
    lines = []
    for fld in fields:
        ann = annotation_of(fld, prims, text)
        desc = field_description(fld.doc, fld.enum, fld.unit)
        if optional:
            default = (defaults or {}).get(fld.name)
            lines.append(
                f"    {fld.name}: Annotated[{ann} | None, Field(description={desc!r})] = "
                f"{default if default is not None else 'None'}\n"
            )
        else:
            lines.append(f"    {fld.name}: Annotated[{ann}, Field(description={desc!r})]\n")
    return lines
