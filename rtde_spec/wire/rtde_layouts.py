"""Every RTDE package's layout, compiled once for the shared engine (`wire.layout`) from the spec."""

from __future__ import annotations

from functools import cache

from rtde_spec._generated.constants import BYTE_ORDER
from rtde_spec.wire.fields import WireField, wire_fields, wire_primitives
from rtde_spec.wire.layout import Layout


@cache
def layouts() -> dict[str, Layout[WireField]]:
    """Every package's layout, compiled once for the shared engine from the spec's fields.

    Read from the generated spec data (validated by the meta-model at codegen time),
    without building the pydantic meta-model: a client or capture starts faster.
    """
    from rtde_spec._generated.spec_data import SPEC

    prims = wire_primitives(SPEC["primitives"]["primitives"])
    return {
        msg["name"]: Layout(wire_fields(msg.get("fields", [])), prims, order=BYTE_ORDER, ascii_only=True)
        for msg in SPEC["packages"]["messages"]
    }
