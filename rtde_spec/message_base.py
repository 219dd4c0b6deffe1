"""Base class of the generated package models, and the layout rows the codec walks."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, ValidationError

from .validation_errors import encode_error

if TYPE_CHECKING:
    from construct import Construct


@dataclass(frozen=True)
class FieldLayout:
    """How one package field sits on the wire, so errors can name its byte offset.

    kind: fixed (a primitive of `size` bytes), prefixed (a uint8 length, then the
    bytes), rest (everything up to the end of the package).
    """

    name: str
    kind: Literal["fixed", "prefixed", "rest"]
    size: int
    text: bool = False


class RtdeMessage(BaseModel):
    """One RTDE package: fields as the spec names them, plus class-level wire metadata."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    NAME: ClassVar[str]
    PACKAGE_TYPE: ClassVar[int]
    PACKAGE_NAME: ClassVar[str]
    SENDERS: ClassVar[tuple[str, ...]]
    PROTOCOLS: ClassVar[tuple[int, ...]]
    STRUCT: ClassVar[Construct]
    LAYOUT: ClassVar[tuple[FieldLayout, ...]]
    ENUMS: ClassVar[dict[str, str]]  # field name -> enum name in spec/
    FIXED_FORMAT: ClassVar[str]  # struct format of the leading fixed-size fields

    def __init__(self, **data: object) -> None:
        """Validate like pydantic, but fail with the library's EncodeError."""
        try:
            super().__init__(**data)
        except ValidationError as exc:
            raise encode_error(exc, type(self).NAME, type(self)) from None

    def to_bytes(self) -> bytes:
        """The whole package, header included."""
        from .codec import encode

        return encode(self)

    def fields(self) -> dict[str, object]:
        """Field values keyed by the spec's field names, in wire order."""
        return {layout.name: getattr(self, layout.name) for layout in self.LAYOUT}
