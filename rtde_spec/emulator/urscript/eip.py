"""The Flexible Ethernet/IP Adapter's handles (the e-Series Script Directory, chapter 20, "Starting
from Polyscope 5.16"): eip_reader_factory(instance_name, data_size) opens PLC->Robot data for
reading, eip_writer_factory(...) Robot->PLC data for writing, and the handle's methods lay out the
instance's bytes under labels (define_uint8 .. define_float32, their _array forms, define_bit,
define_string) and read or write them by label.

The emulator has no Ethernet/IP adapter and no PLC: a reader reads what no PLC wrote (zeros, False,
""), a writer keeps what the program wrote (`values`), checked against its label's type as the
controller checks it. A watchdog is recorded and never trips.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from rtde_spec.emulator.urscript.calls import arg, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.matrices import MAX_ELEMENTS
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.values import INT_MAX, INT_MIN

# a numeric field's bytes and its values (None: any float a float32 holds)
NUMERIC: dict[str, tuple[int, tuple[int, int] | None]] = {
    "uint8": (1, (0, 0xFF)),
    "uint16": (2, (0, 0xFFFF)),
    "int16": (2, (-0x8000, 0x7FFF)),
    "int32": (4, (INT_MIN, INT_MAX)),  # URScript's own int
    "float32": (4, None),
}
FLOAT32_MAX = 3.4028234663852886e38
WATCHDOG_ACTIONS = {0: "ignore", 1: "pause", 2: "stop"}


@dataclass
class Label:
    kind: str  # a NUMERIC key, "bit" or "string"
    start: int  # the first byte, or for a bit its bit from the instance's start
    end: int  # past the last byte (past the bit for a bit)
    count: int = 0  # elements of an array (0: one value), characters of a string


@dataclass
class EipHandle:
    instance: str
    size: int
    writer: bool
    labels: dict[str, Label] = field(default_factory=dict)
    values: dict[str, Any] = field(default_factory=dict)  # what the program wrote
    watchdog: tuple[float, int] | None = None
    watching: bool = False
    closed: bool = False

    def __repr__(self) -> str:
        return f"<{'writer' if self.writer else 'reader'} handle of instance {self.instance}>"


def _factory(writer: bool, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> EipHandle:
    instance = arg(stmt, args, kwargs, 0, "instance_name")
    size = arg(stmt, args, kwargs, 1, "data_size")
    if not isinstance(instance, str) or not instance:
        raise ScriptFault(
            f"{stmt.name}: instance_name must be a text (the instance id), not {instance!r}", stmt.line, 1
        )
    if type(size) is not int or not 0 < size <= MAX_ELEMENTS:
        raise ScriptFault(
            f"{stmt.name}: data_size must be an int of 1 to {MAX_ELEMENTS} bytes, not {size!r}", stmt.line, 1
        )
    return EipHandle(instance, size, writer)


def eip_reader_factory(runner: Runner, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> EipHandle:
    """A handle on PLC->Robot data: read only."""
    return _factory(False, stmt, args, kwargs)


def eip_writer_factory(runner: Runner, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> EipHandle:
    """A handle on Robot->PLC data: write only."""
    return _factory(True, stmt, args, kwargs)


def call(
    handle: EipHandle, name: str, args: list[Any], kwargs: dict[str, Any], line: int, column: int
) -> Any:
    """`handle.name(args)`: a layout definition, a read, a write or a watchdog setting."""

    def fault(text: str) -> ScriptFault:
        return ScriptFault(f"{name}: {text}", line, column)

    if kwargs:
        if name != "define_bit" or set(kwargs) != {"bitfield_width"} or len(args) != 3:
            raise fault("takes its arguments in order (define_bit's bitfield_width may be named)")
        args = [*args, kwargs["bitfield_width"]]
    if handle.closed:
        raise fault("the handle is closed (a new one has to be made)")
    kind = name.removeprefix("define_").removesuffix("_array")
    if name.startswith("define_") and (kind in NUMERIC or kind in ("bit", "string")):
        _define(handle, name, kind, args, fault)
        return None
    method = _METHODS.get(name)
    if method is None:
        raise fault(f"an Ethernet/IP handle has no method {name}")
    return method(handle, args, fault)


def _ints(args: list[Any], count: int, names: tuple[str, ...], fault: Any) -> list[int]:
    if len(args) != count or not all(type(a) is int for a in args[: len(names)]):
        raise fault(f"takes ({', '.join(names)}, data_name), ints and a text")
    return [int(a) for a in args[: len(names)]]


def _define(handle: EipHandle, name: str, kind: str, args: list[Any], fault: Any) -> None:
    if kind == "bit":
        if len(args) not in (3, 4):
            raise fault("takes (offset, bit_number, data_name, bitfield_width=1)")
        offset, bit = _ints(args[:2], 2, ("offset", "bit_number"), fault)
        label, width = args[2], args[3] if len(args) == 4 else 1
        if type(width) is not int or width not in (1, 2, 4):
            raise fault(f"bitfield_width must be 1, 2 or 4, not {width!r}")
        if not 0 <= bit < 8 * width:
            raise fault(f"bit_number must be 0 to {8 * width - 1} in a field of {width} bytes, not {bit}")
        new = Label("bit", offset * 8 + bit, offset * 8 + bit + 1)
        last = offset + width
    elif kind == "string" or name.endswith("_array"):
        offset, count = _ints(args, 3, ("offset", "length"), fault)
        label = args[2]
        if count < 1:
            raise fault(f"length must be 1 or more, not {count}")
        each = 1 if kind == "string" else NUMERIC[kind][0]
        new = Label(kind, offset, offset + count * each, count)
        last = new.end
    else:
        (offset,) = _ints(args, 2, ("offset",), fault)
        label = args[1]
        new = Label(kind, offset, offset + NUMERIC[kind][0])
        last = new.end
    if not isinstance(label, str) or not label:
        raise fault(f"data_name must be a text that is not empty, not {label!r}")
    if offset < 0 or last > handle.size:
        raise fault(f"{label!r} does not fit in the instance's {handle.size} bytes")
    for other_name, other in handle.labels.items():
        if other_name != label and _overlap(new, other):
            raise fault(f"{label!r} overlaps {other_name!r}")
    handle.labels[label] = new


def _overlap(a: Label, b: Label) -> bool:
    """Bits may share bytes with numbers (not with strings or other bits), numbers not with each other."""
    if (a.kind == "bit") != (b.kind == "bit"):
        byte_a = (a.start // 8, a.start // 8 + 1) if a.kind == "bit" else (a.start, a.end)
        byte_b = (b.start // 8, b.start // 8 + 1) if b.kind == "bit" else (b.start, b.end)
        return "string" in (a.kind, b.kind) and byte_a[0] < byte_b[1] and byte_b[0] < byte_a[1]
    return a.start < b.end and b.start < a.end


def _zero(label: Label) -> Any:
    one: Any = False if label.kind == "bit" else 0.0 if label.kind == "float32" else 0
    if label.kind == "string":
        return ""
    return [one] * label.count if label.count else one


def _read(handle: EipHandle, args: list[Any], fault: Any) -> Any:
    """One label's value, or a struct of several (no PLC writes: zeros)."""
    if handle.writer:
        raise fault("a writer handle cannot be read")
    if len(args) != 1:
        raise fault("takes data_names: a label or a list of labels")
    names = args[0]
    for one in names if isinstance(names, list) else [names]:
        if one not in handle.labels:
            raise fault(f"no label {str(one)[:40]!r} defined on the handle")
    if isinstance(names, list):
        return {one: _zero(handle.labels[one]) for one in names}
    return _zero(handle.labels[names])


def _write(handle: EipHandle, args: list[Any], fault: Any) -> None:
    """Every label of the struct at once, each value checked against its label's type."""
    if not handle.writer:
        raise fault("a reader handle cannot be written")
    if len(args) != 1 or not isinstance(args[0], dict):
        raise fault(f"takes a struct of labels and values, not {type_name(args[0]) if args else 'nothing'}")
    for label, value in args[0].items():
        if label not in handle.labels:
            raise fault(f"no label {label!r} defined on the handle")
        _check(handle.labels[label], label, value, fault)
    handle.values.update(args[0])


def _check(label: Label, name: str, value: Any, fault: Any) -> None:
    if label.kind == "string":
        if not isinstance(value, str) or len(value) >= label.count:
            raise fault(f"{name!r} takes a text of at most {label.count - 1} characters")
        return
    if label.count and (not isinstance(value, list) or not 0 < len(value) <= label.count):
        raise fault(f"{name!r} takes a list of 1 to {label.count} values")
    values = value if label.count else [value]
    for one in values:
        if label.kind == "bit":
            ok = isinstance(one, bool)
        elif label.kind == "float32":
            number = isinstance(one, (int, float)) and not isinstance(one, bool)
            ok = number and (math.isnan(one) or abs(one) <= FLOAT32_MAX)
        else:
            low, top = NUMERIC[label.kind][1] or (0, 0)
            ok = type(one) is int and low <= one <= top
        if not ok:
            raise fault(f"{one!r} is out of range for {name!r} ({label.kind})"[:200])


def _clear(handle: EipHandle, args: list[Any], fault: Any) -> None:
    if not handle.writer:
        raise fault("only a writer handle can be cleared")
    handle.values.clear()


def _set_watchdog(handle: EipHandle, args: list[Any], fault: Any) -> None:
    if handle.writer:
        raise fault("only a reader handle has a watchdog")
    if len(args) != 2 or not isinstance(args[0], (int, float)) or isinstance(args[0], bool):
        raise fault("takes frequency (a number) and action (0 ignore, 1 pause, 2 stop)")
    frequency, action = float(args[0]), args[1]
    if not 0 < frequency <= 10 or type(action) is not int or action not in WATCHDOG_ACTIONS:
        raise fault(
            f"frequency must be over 0 and at most 10 Hz and action 0-2, not {frequency:g}, {action!r}"
        )
    handle.watchdog, handle.watching = (frequency, action), True


def _watch(on: bool) -> Any:
    def switch(handle: EipHandle, args: list[Any], fault: Any) -> None:
        if handle.watchdog is None:
            raise fault("no watchdog is registered (set_watchdog registers one)")
        handle.watching = on

    return switch


def _close(handle: EipHandle, args: list[Any], fault: Any) -> None:
    handle.closed = True


_METHODS = {
    "read": _read, "write": _write, "clear": _clear, "set_watchdog": _set_watchdog,
    "start_watchdog": _watch(True), "stop_watchdog": _watch(False), "close": _close,
}  # fmt: skip

FACTORIES = {"eip_reader_factory": eip_reader_factory, "eip_writer_factory": eip_writer_factory}
