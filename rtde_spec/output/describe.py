"""Human-readable values: enum names and set bits next to the raw number."""

from __future__ import annotations

from typing import Any

from rtde_spec._generated.enums import BITFIELDS, ENUMS


def enum_name(enum: str, value: int) -> str | None:
    """The member name of `value` in enum `enum`, or None when the spec lists none."""
    cls = ENUMS.get(enum)
    if cls is None:
        return None
    try:
        return cls(value).name
    except ValueError:
        return None


def bit_names(bitfield: str, value: int) -> list[str]:
    """Names of the set bits that the spec names (unnamed bits are left out)."""
    cls = BITFIELDS.get(bitfield)
    if cls is None:
        return []
    return [m.name for m in cls if m.name and value & m.value]


def describe(value: Any, enum: str | None = None, bits: str | None = None) -> str:
    """'3 (INFO_MESSAGE)', '0x5 (POWER_ON|TEACH_BUTTON_PRESSED)', '[1.0, 2.0]', 'text'."""
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).hex() or "(empty)"
    if isinstance(value, (list, tuple)):
        if enum is not None:
            return "[" + ", ".join(describe(v, enum) for v in value) + "]"
        return "[" + ", ".join(describe(v) for v in value) + "]"
    if isinstance(value, bool) or not isinstance(value, int):
        return repr(value) if isinstance(value, str) else str(value)
    if enum is not None:
        name = enum_name(enum, value)
        return f"{value} ({name})" if name else f"{value} (unlisted)"
    if bits is not None:
        names = bit_names(bits, value)
        return f"0x{value:X} ({'|'.join(names) or 'none'})"
    return str(value)
