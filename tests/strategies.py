"""hypothesis strategies drawn from the spec, so new packages are covered unasked."""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from rtde_spec.metamodel.catalogue import Catalogue, WireTypeInfo
from rtde_spec.metamodel.schema import PackageField
from rtde_spec.wire.rtde_messages import RtdeMessage

SPEC = Catalogue.builtin().spec
PRIMS = {p.name: p for p in SPEC.primitives.primitives}
MESSAGES = {m.name: m for m in SPEC.packages.messages}

ascii_text = st.text(alphabet=st.characters(max_codepoint=127))
name_text = st.text(alphabet=st.characters(max_codepoint=127, blacklist_characters=","))


def _primitive(name: str, allow_nan: bool) -> st.SearchStrategy[Any]:
    prim = PRIMS[name]
    if prim.kind == "bool":
        return st.booleans()
    if prim.kind == "int":
        low, high = prim.bounds  # type: ignore[misc]
        return st.integers(low, high)
    return st.floats(allow_nan=allow_nan, width=prim.size * 8)


def field_strategy(fld: PackageField, allow_nan: bool = False) -> st.SearchStrategy[Any]:
    if fld.type == "bytes":
        return st.binary(max_size=600)
    if fld.type == "string":
        if fld.format == "csv":
            return st.lists(name_text, min_size=1, max_size=20)
        return ascii_text.filter(lambda s: len(s) <= 255) if fld.length == "uint8" else ascii_text
    return _primitive(fld.type, allow_nan)


def message_strategy(cls: type[RtdeMessage], allow_nan: bool = False) -> st.SearchStrategy[Any]:
    spec = MESSAGES[cls.NAME]
    return st.builds(cls, **{f.name: field_strategy(f, allow_nan) for f in spec.fields})


def wire_value(wire: WireTypeInfo, allow_nan: bool = False) -> st.SearchStrategy[Any]:
    """A value of an RTDE data type as a recipe codec takes it."""
    assert wire.element is not None
    one = _primitive(wire.element, allow_nan)
    return one if wire.count == 1 else st.tuples(*[one] * wire.count)
