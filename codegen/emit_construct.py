"""The one construct emitter of a layout field, for RTDE packages and primary messages alike.

Both protocols' structs (emit_rtde, emit_primary) are bodies of these fields; only
the text encoding differs (RTDE text is ASCII, the primary interface's UTF-8).
"""

from __future__ import annotations

from rtde_spec.metamodel.schema import CaseSpec, LayoutField, Primitive, Spec

#: construct's name for each struct format character of spec/common/primitives.yaml
CONSTRUCT_BY_STRUCT = {
    "?": "Flag",
    "B": "Int8ub",
    "b": "Int8sb",
    "H": "Int16ub",
    "h": "Int16sb",
    "I": "Int32ub",
    "i": "Int32sb",
    "Q": "Int64ub",
    "q": "Int64sb",
    "f": "Float32b",
    "d": "Float64b",
}


def prims_of(spec: Spec) -> dict[str, Primitive]:
    return {p.name: p for p in spec.primitives.primitives}


def construct_of(
    fld: LayoutField, prims: dict[str, Primitive], indent: str = "    ", text: str = "utf8"
) -> str:
    """The construct expression of one field (groups nest as Structs at `indent`)."""
    kind = fld.kind
    c = CONSTRUCT_BY_STRUCT
    if kind == "value":
        one = c[prims[fld.type or ""].struct]
        return f"Array({fld.count}, {one})" if fld.count else one
    if kind in ("string", "bytes"):
        if fld.length == "rest":
            if kind == "bytes":
                return "GreedyBytes"
            return {"lines": "lines_string()", "csv": "csv_string()"}.get(
                fld.format or "", f'GreedyString("{text}")'
            )
        prefix = c[prims[fld.length or ""].struct]
        if kind == "bytes":
            return f"Prefixed({prefix}, GreedyBytes)"
        return (
            f"prefixed_or_rest({prefix})" if fld.fallback == "rest" else f'PascalString({prefix}, "{text}")'
        )
    if kind == "values":
        return "GreedyBytes  # typed values: rtde_spec.wire.primary_values"
    if kind == "switch":
        cases = []
        for value, case in (fld.cases or {}).items():
            if isinstance(case, CaseSpec):
                cases.append(f'{value}: PascalString({c[prims[case.length or ""].struct]}, "{text}")')
            else:
                cases.append(f"{value}: {c[prims[case].struct]}")
        return f"Switch(this.{fld.switch}, {{{', '.join(cases)}}})"
    inner = struct_body(fld.fields or [], prims, indent + "    ", text)
    if kind == "optional":
        return f"If(this.{fld.when}, Struct(\n{inner}{indent}))"
    if isinstance(fld.repeat, int):
        return f"Array({fld.repeat}, Struct(\n{inner}{indent}))"
    return f"GreedyRange(Struct(\n{inner}{indent}))"


def struct_body(
    fields: list[LayoutField], prims: dict[str, Primitive], indent: str, text: str = "utf8"
) -> str:
    """The lines inside a Struct(...) of these fields."""
    return "".join(f'{indent}"{f.name}" / {construct_of(f, prims, indent, text)},\n' for f in fields)
