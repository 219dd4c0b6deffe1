"""The one layout engine: spec fields compiled into a decoder and an encoder.

RTDE packages and primary/secondary messages are both described by `LayoutField`s
and decoded here, each package parsed once.

Runs of fixed-size fields — primitives, arrays, groups repeated a fixed number of
times — become one struct.Struct plus one generated regrouping function, so a
Robot State sub-package decodes with one unpack. Strings, switches, conditional
and open-ended groups are stepped through one by one.

Decoding follows the interface's compatibility rule: a part shorter than its
layout yields the fields present and the names of those missing; bytes after
the layout are returned for the caller to keep. Inconsistent data (a length
prefix past the end) is a DecodeError with the byte offset.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from rtde_spec._generated.constants import PRIMARY_BYTE_ORDER
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.wire.fields import CaseLike, FieldLike, PrimitiveLike

if TYPE_CHECKING:
    from rtde_spec.wire.primary_values import ValueTable

Values = dict[str, Any]
F = TypeVar("F", bound=FieldLike)  # the meta-model's LayoutField or the runtime's WireField


@dataclass
class Atom:
    """The smallest piece a short part is decoded in: a value or a whole fixed group."""

    name: str
    fmt: str
    size: int
    expr: Callable[[int], tuple[str, int]]  # flat index -> (python expression, next index)
    order: str  # struct's byte-order prefix
    struct: struct.Struct = field(init=False)
    regroup: Callable[[tuple[Any, ...]], Any] = field(init=False)

    def __post_init__(self) -> None:
        self.struct = struct.Struct(self.order + self.fmt)
        source, _ = self.expr(0)
        self.regroup = eval(f"lambda t: {source}")


@dataclass
class FixedStep:
    atoms: list[Atom]
    order: str
    struct: struct.Struct = field(init=False)
    regroup: Callable[[tuple[Any, ...]], Values] = field(init=False)

    def __post_init__(self) -> None:
        self.struct = struct.Struct(self.order + "".join(a.fmt for a in self.atoms))
        parts = []
        index = 0
        for atom in self.atoms:
            source, index = atom.expr(index)
            parts.append(f"{atom.name!r}: {source}")
        self.regroup = eval(f"lambda t: {{{', '.join(parts)}}}")


class Layout(Generic[F]):
    """Decoder and encoder of one list of layout fields."""

    def __init__(
        self,
        fields: Sequence[F],
        prims: Mapping[str, PrimitiveLike],
        values: ValueTable | None = None,
        *,
        order: str = PRIMARY_BYTE_ORDER,
        ascii_only: bool = False,
    ) -> None:
        """`values` decodes typed global-variable values (primary); `ascii_only` refuses other text (RTDE)."""
        self.order, self.ascii_only = order, ascii_only
        self.fields = fields
        self.prims = prims
        self.value_table = values
        self.names = [f.name for f in fields]
        self.group_fields = [f for f in fields if f.fields is not None]
        self.steps: list[FixedStep | F] = []
        self.groups: dict[str, Layout[Any]] = {}
        run: list[Atom] = []
        for fld in fields:
            if fld.fields is not None:
                self.groups[fld.name] = Layout(fld.fields, prims, values, order=order, ascii_only=ascii_only)
            atom = self._atom(fld)
            if atom is not None:
                run.append(atom)
                continue
            if run:
                self.steps.append(FixedStep(run, order))
                run = []
            self.steps.append(fld)
        if run:
            self.steps.append(FixedStep(run, order))
        only = self.steps[0] if len(self.steps) == 1 else None
        self._single: FixedStep | None = only if isinstance(only, FixedStep) else None
        fixed_steps = [s for s in self.steps if isinstance(s, FixedStep)]
        fixed = len(fixed_steps) == len(self.steps)
        self.fixed_size: int | None = sum(s.struct.size for s in fixed_steps) if fixed else None

    # --- compilation --------------------------------------------------------

    def _atom(self, fld: FieldLike) -> Atom | None:
        kind = fld.kind
        if kind == "value":
            prim = self.prims[fld.type or ""]
            count = fld.count or 1
            scale = fld.scale

            def value_expr(i: int, count: int = count, scale: float | None = scale) -> tuple[str, int]:
                if scale is not None:  # the wire holds value x scale: SI values out, one division each
                    parts = [f"t[{j}] / {scale!r}" for j in range(i, i + count)]
                    return (parts[0] if fld.count is None else f"({', '.join(parts)},)"), i + count
                return (f"t[{i}]" if count == 1 else f"t[{i}:{i + count}]"), i + count

            return Atom(fld.name, prim.struct * count, prim.size * count, value_expr, self.order)
        if kind == "repeat" and isinstance(fld.repeat, int):
            inner = [self._atom(f) for f in fld.fields or []]
            if any(a is None for a in inner):
                return None
            atoms = [a for a in inner if a is not None]
            times = fld.repeat

            def group_expr(i: int, atoms: list[Atom] = atoms, times: int = times) -> tuple[str, int]:
                entries = []
                for _ in range(times):
                    parts = []
                    for atom in atoms:
                        source, i = atom.expr(i)
                        parts.append(f"{atom.name!r}: {source}")
                    entries.append("{" + ", ".join(parts) + "}")
                return "[" + ", ".join(entries) + "]", i

            fmt = "".join(a.fmt for a in atoms) * times
            return Atom(fld.name, fmt, sum(a.size for a in atoms) * times, group_expr, self.order)
        return None

    # --- decoding -----------------------------------------------------------

    def decode(self, buf: bytes, pos: int, end: int, where: str = "") -> tuple[Values, list[str], int]:
        """(values, missing field names, position after the last decoded byte)."""
        if self._single is not None and end - pos >= self._single.struct.size:
            # the common case: one fixed run, all there
            return (
                self._single.regroup(self._single.struct.unpack_from(buf, pos)),
                [],
                pos + self._single.struct.size,
            )
        values: Values = {}
        for index, step in enumerate(self.steps):
            if isinstance(step, FixedStep):
                size = step.struct.size
                if end - pos >= size:
                    values.update(step.regroup(step.struct.unpack_from(buf, pos)))
                    pos += size
                    continue
                for j, atom in enumerate(step.atoms):
                    if end - pos < atom.size:
                        return values, self._missing_from(index, j), pos
                    values[atom.name] = atom.regroup(atom.struct.unpack_from(buf, pos))
                    pos += atom.size
                continue
            ok, pos = self._decode_field(step, buf, pos, end, values, where)
            if not ok:
                return values, self._missing_from(index, 0), pos
        return values, [], pos

    def _missing_from(self, step_index: int, atom_index: int) -> list[str]:
        names: list[str] = []
        for index, step in enumerate(self.steps[step_index:]):
            if isinstance(step, FixedStep):
                start = atom_index if index == 0 else 0
                names += [a.name for a in step.atoms[start:]]
            else:
                names.append(step.name)
        return names

    def _prefix_fits(self, buf: bytes, pos: int, end: int, prefix_type: str) -> bool:
        """Whether a length prefix at `pos` counts exactly the bytes up to `end`."""
        size = self.prims[prefix_type].size
        if end - pos < size:
            return end == pos  # nothing at all: the field is missing, as without fallback
        return int.from_bytes(buf[pos : pos + size], "big") == end - pos - size

    def _prefixed(
        self, buf: bytes, pos: int, end: int, prefix_type: str, fld: str
    ) -> tuple[bytes | None, int]:
        prim = self.prims[prefix_type]
        if end - pos < prim.size:
            return None, pos
        length = int.from_bytes(buf[pos : pos + prim.size], "big", signed=bool(prim.signed))
        start = pos + prim.size
        if length < 0 or end - start < length:
            raise DecodeError(
                f"length prefix says {length} bytes but the part ends first",
                field=fld,
                offset=pos,
                expected=f"{length} bytes",
                actual=f"{end - start} bytes",
            )
        return bytes(buf[start : start + length]), start + length

    def _decode_field(
        self, fld: FieldLike, buf: bytes, pos: int, end: int, values: Values, where: str
    ) -> tuple[bool, int]:
        name = f"{where}{fld.name}"
        kind = fld.kind
        if kind in ("string", "bytes"):
            raw: bytes | None
            if fld.length == "rest" and fld.format == "lines":
                # names end with a newline; an unterminated tail stays as extra bytes
                stop = bytes(buf[pos:end]).rfind(b"\n") + 1
                raw, pos = bytes(buf[pos : pos + stop]), pos + stop
            elif fld.length == "rest":
                raw, pos = bytes(buf[pos:end]), end
            elif fld.fallback == "rest" and not self._prefix_fits(buf, pos, end, fld.length or ""):
                raw, pos = bytes(buf[pos:end]), end  # peers send it without the prefix
            else:
                raw, pos = self._prefixed(buf, pos, end, fld.length or "", name)
                if raw is None:
                    return False, pos
            if kind == "string" and self.ascii_only:
                bad = next((i for i, b in enumerate(raw) if b > 0x7F), None)
                if bad is not None:
                    raise DecodeError(
                        "text is not ASCII",
                        field=name,
                        offset=pos - len(raw) + bad,
                        expected="bytes 0x00..0x7f",
                        actual=f"0x{raw[bad]:02x}",
                    )
            values[fld.name] = _text(raw, fld.format) if kind == "string" else raw
            return True, pos
        if kind == "values":
            assert self.value_table is not None, "typed values need a ValueTable"
            values[fld.name] = self.value_table.decode_all(buf, pos, end, name)
            return True, end
        if kind == "switch":
            case = _case(fld, values)
            if case is None:
                values[fld.name] = None  # an unknown case: the rest stays as extra bytes
                return True, pos
            if not isinstance(case, str):  # a length-prefixed text
                text, pos = self._prefixed(buf, pos, end, case.length or "", name)
                if text is None:
                    return False, pos
                values[fld.name] = text.decode("utf-8", "surrogateescape")
                return True, pos
            prim = self.prims[case]
            if end - pos < prim.size:
                return False, pos
            (values[fld.name],) = struct.unpack_from(self.order + prim.struct, buf, pos)
            return True, pos + prim.size
        inner = self.groups[fld.name]
        if kind == "optional":
            if not values.get(fld.when or ""):
                values[fld.name] = None
                return True, pos
            group, missing, new_pos = inner.decode(buf, pos, end, f"{name}.")
            if missing:
                return False, pos
            values[fld.name] = group
            return True, new_pos
        entries: list[Values] = []
        while pos < end:  # repeat until the end of the part
            group, missing, new_pos = inner.decode(buf, pos, end, f"{name}[{len(entries)}].")
            if missing:
                raise DecodeError(
                    f"entry {len(entries)} is cut off by the end of the part",
                    field=name,
                    offset=pos,
                    expected=f"fields {', '.join(missing)}",
                )
            entries.append(group)
            pos = new_pos
        values[fld.name] = entries
        return True, pos

    # --- encoding -----------------------------------------------------------

    def encode(self, values: Mapping[str, Any], where: str = "") -> bytes:
        """Bytes of the fields present; fields after the first absent one must be absent too."""
        out = bytearray()
        absent: str | None = None
        for fld in self.fields:
            value = values.get(fld.name)
            conditional_off = fld.kind == "optional" and not values.get(fld.when or "")
            unknown_case = fld.kind == "switch" and _case(fld, values) is None
            if value is None and not (conditional_off or unknown_case):
                absent = absent or fld.name
                continue
            if absent is not None and value is not None:
                raise EncodeError(
                    f"set, but the earlier field {absent} is absent (fields are a prefix)",
                    field=f"{where}{fld.name}",
                )
            if value is not None:
                out += self._encode_field(fld, value, values, f"{where}{fld.name}")
        return bytes(out)

    def _encode_field(self, fld: FieldLike, value: Any, values: Mapping[str, Any], name: str) -> bytes:
        kind = fld.kind
        try:
            if kind == "value":
                prim = self.prims[fld.type or ""]
                items = tuple(value) if fld.count else (value,)
                if fld.count and len(items) != fld.count:
                    raise EncodeError(f"needs exactly {fld.count} values", field=name, actual=len(items))
                if fld.scale is not None:  # SI values in, value x scale on the wire (rounded for integers)
                    items = tuple(_scaled(v, fld.scale, prim.kind, name) for v in items)
                return struct.pack(self.order + prim.struct * len(items), *items)
            if kind in ("string", "bytes"):
                raw = _untext(value, fld.format) if kind == "string" else bytes(value)
                return raw if fld.length == "rest" else self._prefix(fld.length or "", len(raw), name) + raw
            if kind == "values":
                assert self.value_table is not None, "typed values need a ValueTable"
                return self.value_table.encode_all(list(value), name)
            if kind == "switch":
                case = (fld.cases or {})[values[fld.switch or ""]]
                if not isinstance(case, str):  # a length-prefixed text
                    raw = str(value).encode("utf-8", "surrogateescape")
                    return self._prefix(case.length or "", len(raw), name) + raw
                return struct.pack(self.order + self.prims[case].struct, value)
            inner = self.groups[fld.name]
            if kind == "optional":
                return inner.encode(_as_dict(value), f"{name}.")
            entries = list(value)
            if isinstance(fld.repeat, int) and len(entries) != fld.repeat:
                raise EncodeError(f"needs exactly {fld.repeat} entries", field=name, actual=len(entries))
            return b"".join(inner.encode(_as_dict(e), f"{name}[{i}].") for i, e in enumerate(entries))
        except struct.error as exc:
            raise EncodeError(f"cannot be packed: {exc}", field=name, actual=repr(value)) from None

    def _prefix(self, prefix_type: str, length: int, name: str) -> bytes:
        prim = self.prims[prefix_type]
        bounds = prim.bounds or (0, 0)
        if not 0 <= length <= bounds[1]:
            raise EncodeError(
                "too long for its length prefix",
                field=name,
                expected=f"<= {bounds[1]} bytes",
                actual=f"{length} bytes",
            )
        return length.to_bytes(prim.size, "big")


def _scaled(value: Any, scale: float, kind: str, name: str) -> Any:
    try:
        wire = float(value) * scale
    except (TypeError, ValueError):
        raise EncodeError("is not a number", field=name, actual=repr(value)) from None
    if kind != "int":
        return wire
    if wire != wire or wire in (float("inf"), float("-inf")):
        raise EncodeError("is not a finite number", field=name, actual=repr(value))
    return round(wire)


def _case(fld: FieldLike, values: Mapping[str, Any]) -> str | CaseLike | None:
    """The switch case the already-decoded selector field picks (None: unknown)."""
    selector = values.get(fld.switch or "")
    return (fld.cases or {}).get(selector) if isinstance(selector, int) else None


def _text(raw: bytes, fmt: str | None) -> Any:
    text = raw.decode("utf-8", "surrogateescape")
    if fmt == "lines":
        names = text.split("\n")
        return names[:-1] if names and names[-1] == "" else names
    if fmt == "csv":
        return text.split(",")
    return text


def _untext(value: Any, fmt: str | None) -> bytes:
    if fmt == "lines":
        text = "".join(f"{n}\n" for n in value)
    elif fmt == "csv":
        text = ",".join(value)
    else:
        text = str(value)
    return text.encode("utf-8", "surrogateescape")


def _as_dict(value: Any) -> Mapping[str, Any]:
    return value if isinstance(value, Mapping) else value.model_dump()
