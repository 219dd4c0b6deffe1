"""hypothesis strategies for primary-interface models, drawn from spec/primary."""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from rtde_spec._generated import primary_models as gen
from rtde_spec.metamodel.schema import CaseSpec, LayoutField
from rtde_spec.wire.primary_values import VariableValue

from .strategies import SPEC, _primitive

text = st.text(alphabet=st.characters(blacklist_categories=["Cs"]), max_size=30)
line_names = st.lists(
    st.text(
        alphabet=st.characters(blacklist_categories=["Cs"], blacklist_characters="\n"),
        min_size=1,
        max_size=10,
    ),
    max_size=5,
)


def _prim(name: str) -> st.SearchStrategy[Any]:
    return _primitive(name, allow_nan=False)


def _values(depth: int = 0) -> st.SearchStrategy[VariableValue]:
    leaves = st.one_of(
        st.just(VariableValue(type="NONE")),
        st.builds(VariableValue, type=st.sampled_from(["CONST_STRING", "VAR_STRING"]), value=text),
        st.builds(VariableValue, type=st.just("POSE"), value=st.tuples(*[_prim("float")] * 6)),
        st.builds(VariableValue, type=st.just("BOOL"), value=st.booleans()),
        st.builds(VariableValue, type=st.sampled_from(["NUM", "FLOAT"]), value=_prim("float")),
        st.builds(VariableValue, type=st.just("INT"), value=_prim("int32")),
    )
    if depth >= 2:
        return leaves
    inner = _values(depth + 1)
    return st.one_of(
        leaves,
        st.builds(VariableValue, type=st.just("LIST"), value=st.lists(inner, max_size=3)),
        st.integers(1, 2).flatmap(
            lambda cols: st.builds(
                VariableValue,
                type=st.just("MATRIX"),
                value=st.lists(st.lists(inner, min_size=cols, max_size=cols), min_size=1, max_size=2),
            )
        ),
    )


def _field(fld: LayoutField, values: dict[str, Any]) -> st.SearchStrategy[Any]:
    kind = fld.kind
    if kind == "value":
        one = _prim(fld.type or "")
        return st.tuples(*[one] * fld.count) if fld.count else one
    if kind == "string":
        return line_names if fld.format == "lines" else text
    if kind == "bytes":
        return st.binary(max_size=40)
    if kind == "values":
        return st.lists(_values(), max_size=4)
    if kind == "switch":
        case = (fld.cases or {}).get(values[fld.switch or ""])
        if case is None:
            return st.none()
        return text if isinstance(case, CaseSpec) else _prim(case)
    group = gen.GROUPS[fld.group or ""]
    entry = _group(group, fld.fields or [])
    if kind == "optional":
        return entry if values.get(fld.when or "") else st.none()
    if isinstance(fld.repeat, int):
        return st.tuples(*[entry] * fld.repeat)
    return st.lists(entry, max_size=3)


def _layout(fields: list[LayoutField]) -> st.SearchStrategy[dict[str, Any]]:
    @st.composite
    def draw(d: st.DrawFn) -> dict[str, Any]:
        values: dict[str, Any] = {}
        for fld in fields:
            values[fld.name] = d(_field(fld, values))
        return values

    return draw()


def _group(cls: type, fields: list[LayoutField]) -> st.SearchStrategy[Any]:
    return _layout(fields).map(lambda v: cls(**v))


def member_strategy(family: str, member_type: int) -> st.SearchStrategy[Any]:
    fam = next(f for f in SPEC.primary.families if f.name == family)
    member = next(m for m in fam.members if m.type == member_type)
    cls = gen.MEMBERS[(family, member_type)]
    fields = [*fam.prefix, *member.fields]

    def fix_tag(values: dict[str, Any]) -> Any:
        if fam.tag:
            values[fam.tag] = member.type
        return cls(**values)

    return _layout(fields).map(fix_tag)


MEMBER_KEYS = sorted(gen.MEMBERS)
