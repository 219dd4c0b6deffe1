"""Two rules of the layout language, shared by the meta-model (`schema`) and the runtime's
plain view of it (`wire.fields`), so both read a field alike. No pydantic here: start-up."""

from __future__ import annotations


def field_kind(type_: str, has_fields: bool, when: str | None, switch: str | None) -> str:
    """value | string | bytes | values | repeat | optional | switch: what a layout field is."""
    if has_fields:
        return "optional" if when is not None else "repeat"
    if switch is not None:
        return "switch"
    if type_ in ("string", "bytes"):
        return type_
    if type_ == "variable_values":
        return "values"
    return "value"


def int_bounds(kind: str, size: int, signed: bool | None) -> tuple[int, int] | None:
    """Inclusive range of an integer primitive of `size` bytes; None for floats and bools."""
    if kind != "int":
        return None
    bits = size * 8
    if signed:
        return (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)
    return (0, (1 << bits) - 1)
