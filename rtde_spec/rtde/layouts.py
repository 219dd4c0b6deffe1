"""Every RTDE package's layout, compiled once for the shared engine (`wire.layout`) from the spec."""

from __future__ import annotations

from functools import cache

from rtde_spec._generated.constants import BYTE_ORDER
from rtde_spec.wire.layout import Layout


@cache
def layouts() -> dict[str, Layout]:
    """Every package's layout, compiled once for the shared engine from the spec's fields."""
    from rtde_spec._generated.spec_data import SPEC
    from rtde_spec.spec.schema import LayoutField, Primitive

    prims = {p["name"]: Primitive.model_validate(p) for p in SPEC["primitives"]["primitives"]}
    out = {}
    for msg in SPEC["packages"]["messages"]:
        fields = [LayoutField.model_validate(f) for f in msg.get("fields", [])]
        out[msg["name"]] = Layout(fields, prims, order=BYTE_ORDER, ascii_only=True)
    return out
