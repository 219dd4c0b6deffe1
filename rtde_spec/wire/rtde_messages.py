"""Base class of the generated package models, and the layout rows the codec walks.

Encoding lives here (not in the codec) so the generated models need nothing that
imports them back; it runs the same layout engine as decoding.
"""

from __future__ import annotations

import importlib
import struct
from functools import cache
from typing import TYPE_CHECKING, Any, ClassVar

from pydantic import BaseModel, ConfigDict, ValidationError

from rtde_spec.errors import EncodeError
from rtde_spec.wire.model_types import WIRE_MODEL_CONFIG
from rtde_spec.wire.pydantic_errors import encode_error
from rtde_spec.wire.rtde_layouts import layouts

if TYPE_CHECKING:
    from construct import Construct


class RtdeMessage(BaseModel):
    """One RTDE package: fields as the spec names them, plus class-level wire metadata."""

    model_config = ConfigDict(**WIRE_MODEL_CONFIG)  # (wire/model_types.py says why each key)

    NAME: ClassVar[str]
    PACKAGE_TYPE: ClassVar[int]
    PACKAGE_NAME: ClassVar[str]
    SENDERS: ClassVar[tuple[str, ...]]
    PROTOCOLS: ClassVar[tuple[int, ...]]
    STRUCT: ClassVar[Construct]
    FIELDS: ClassVar[tuple[str, ...]]  # field names in wire order; layout: wire/rtde_layouts.py
    ENUMS: ClassVar[dict[str, str]]  # field name -> enum name in spec/
    FIXED_FORMAT: ClassVar[str]  # struct format of the leading fixed-size fields
    HEADER_FORMAT: ClassVar[str]  # struct format of the header (size, type)
    MAX_SIZE: ClassVar[int]  # largest package the size field can count

    def __init__(self, **data: object) -> None:
        """Validate like pydantic, but fail with the library's EncodeError."""
        try:
            super().__init__(**data)
        except ValidationError as exc:
            raise encode_error(exc, type(self).NAME, type(self)) from None

    def to_bytes(self) -> bytes:
        """The whole package, header included."""
        cls = type(self)
        values: dict[str, Any] = {name: getattr(self, name) for name in cls.FIELDS}
        # models built with model_construct skip validation; check again here
        cls(**values)
        try:
            body = layouts()[cls.NAME].encode(values)
        except EncodeError as exc:
            raise exc.relocated(package=cls.NAME) from None
        header = _header(cls.HEADER_FORMAT)
        size = header.size + len(body)
        if size > cls.MAX_SIZE:
            raise EncodeError(
                "package too large for the size field",
                package=cls.NAME,
                field="size",
                expected=f"<= {cls.MAX_SIZE} bytes",
                actual=f"{size} bytes",
            )
        return header.pack(size, cls.PACKAGE_TYPE) + body

    def fields(self) -> dict[str, object]:
        """Field values keyed by the spec's field names, in wire order."""
        return {name: getattr(self, name) for name in self.FIELDS}


@cache
def _header(fmt: str) -> struct.Struct:
    return struct.Struct(fmt)


class _StructOf:
    """`Model.STRUCT`: the package's construct struct, imported on first use (construct and the
    generated structs cost a capture or a client ~25 ms of start-up they do not need). The
    generated model names the module, so this floor names nothing above it."""

    def __init__(self, module: str, name: str) -> None:
        self.module, self.name = module, name

    def __get__(self, obj: object, owner: type | None = None) -> Construct:
        return getattr(importlib.import_module(self.module), self.name)  # type: ignore[no-any-return]


def struct_of(module: str, name: str) -> Any:
    """The value of a generated model's STRUCT: `<module>.<name>`, imported when read."""
    return _StructOf(module, name)
