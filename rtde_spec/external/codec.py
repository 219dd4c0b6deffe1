"""Decoders and encoders of URCL's external-control records, compiled from the spec.

Every record is a fixed number of int32 words; each reading of it (a variant, chosen
by the selector word) is a `Layout` of the one engine, so it decodes with one
`struct` unpack and its scaled words come out divided by their scale (SI units).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from functools import cache
from typing import Any

from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.external import ExternalControlFile, ExternalProtocol, Variant, external_spec
from rtde_spec.metamodel.schema import Primitive
from rtde_spec.wire.layout import Layout

ORDER = {"big": ">", "little": "<"}


@dataclass
class VariantPlan:
    """One variant compiled: its layout, the table its rows go to, its enum-valued fields."""

    spec: Variant
    layout: Layout
    enums: dict[str, frozenset[int]]  # field -> the values its enum knows

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def table(self) -> str:
        return self.spec.table


class RecordCodec:
    """One message of one protocol (a reverse command, a trajectory point, ...), all its variants.

    `layout` picks a layout by name (the spec's `older` entries, or the newest's `layout`
    name); default: the newest.
    """

    def __init__(
        self,
        protocol: str,
        message: str,
        layout: str | None = None,
        spec: ExternalControlFile | None = None,
        prims: dict[str, Primitive] | None = None,
    ) -> None:
        spec = spec or external_spec()
        prims = prims or {p.name: p for p in Catalogue.builtin().spec.primitives.primitives}
        proto = spec.protocol(protocol)
        msg = next((m for m in proto.messages if m.name == message), None)
        if msg is None:
            raise KeyError(f"protocol {protocol} has no message {message}")
        self.protocol, self.message, self.sender = protocol, message, msg.sender
        newest = layout is None or layout == msg.layout
        record = msg if newest else next((o for o in msg.older if o.name == layout), None)
        if record is None:
            known = ", ".join(o.name for o in msg.older) or "none"
            raise KeyError(f"message {message} has no older layout {layout} (known: {known})")
        self.layout = msg.layout if newest else layout  # the layout's name (None: a message of one layout)
        order = ORDER[spec.byte_order]
        enum_values = {e.name: frozenset(v.value for v in e.values) for e in spec.enums}
        self.size = record.record_bytes
        self.variants: list[VariantPlan] = []
        self.by_value: dict[int, VariantPlan] = {}
        self.default: VariantPlan | None = None
        self.selector: struct.Struct | None = None
        self.selector_at = 0
        self.selector_name = record.selector or ""
        for variant in record.variants:
            plan = VariantPlan(
                variant,
                Layout(variant.fields, prims, order=order),
                {f.name: enum_values[f.enum] for f in variant.fields if f.enum},
            )
            self.variants.append(plan)
            for value in variant.when or []:
                self.by_value[value] = plan
            if variant.when is None:
                self.default = plan
            if record.selector is not None and self.selector is None:
                pos = 0
                for f in variant.fields:
                    if f.name == record.selector:
                        self.selector = struct.Struct(order + prims[f.type].struct)
                        self.selector_at = pos
                    pos += prims[f.type].size * (f.count or 1)

    def variant_of(self, buf: bytes | bytearray | memoryview, at: int = 0) -> VariantPlan | None:
        """The variant the selector word picks (the default for a value no variant names)."""
        if self.selector is None:
            return self.variants[0]
        (value,) = self.selector.unpack_from(buf, at + self.selector_at)
        return self.by_value.get(value, self.default)

    def decode(self, buf: bytes | bytearray | memoryview, at: int = 0) -> tuple[VariantPlan, dict[str, Any]]:
        """(variant, values in SI units) of the record at `at`; DecodeError when cut or of no variant."""
        if at < 0 or at > len(buf):
            raise DecodeError(
                "offset outside the buffer", field=self.message, offset=at, expected=f"0 to {len(buf)}"
            )
        if len(buf) - at < self.size:
            raise DecodeError(
                f"{self.message} is cut off",
                field=self.message,
                offset=at,
                expected=f"{self.size} bytes",
                actual=f"{len(buf) - at} bytes",
            )
        plan = self.variant_of(buf, at)
        if plan is None:
            assert self.selector is not None
            raise DecodeError(
                "no variant for this selector value",
                field=f"{self.message}.{self.selector_name}",
                offset=at + self.selector_at,
                actual=self.selector.unpack_from(buf, at + self.selector_at)[0],
            )
        values, _, _ = plan.layout.decode(bytes(buf[at : at + self.size]), 0, self.size, f"{self.message}.")
        return plan, values

    def plausible(self, buf: bytes | bytearray | memoryview, at: int = 0) -> bool:
        """Whether a record at `at` looks like one: a variant, every enum word a known value."""
        try:
            plan, values = self.decode(buf, at)
        except DecodeError:
            return False
        return all(values.get(name) in known for name, known in plan.enums.items())

    def encode(self, variant: str, values: dict[str, Any]) -> bytes:
        """A whole record of the named variant (SI values in), zero-padded to the record size."""
        plan = next((v for v in self.variants if v.name == variant), None)
        if plan is None:
            raise EncodeError(f"no variant {variant!r}", field=self.message)
        body = plan.layout.encode(values, f"{self.message}.")
        if len(body) != plan.layout.fixed_size:
            missing = [f.name for f in plan.layout.fields if f.name not in values]
            raise EncodeError(
                f"every field needs a value; missing: {', '.join(missing)}", field=f"{self.message}.{variant}"
            )
        return body + bytes(self.size - len(body))


@cache
def record_codec(protocol: str, message: str, layout: str | None = None) -> RecordCodec:
    """The built-in spec's codec for one message (compiled once per process)."""
    return RecordCodec(protocol, message, layout)


def protocol_codecs(protocol: ExternalProtocol) -> dict[str, RecordCodec]:
    """sender ("driver" or "robot") -> the codec of what that side sends on this protocol."""
    return {m.sender: record_codec(protocol.name, m.name) for m in protocol.messages}
