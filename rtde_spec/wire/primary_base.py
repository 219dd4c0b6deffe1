"""Base classes of the generated primary-interface models, and the models for what
the spec does not know (unknown types are kept, never dropped)."""

from __future__ import annotations

from typing import Any, ClassVar

from pydantic import BaseModel, ConfigDict, ValidationError

from rtde_spec.wire.model_types import WIRE_MODEL_CONFIG
from rtde_spec.wire.pydantic_errors import encode_error

# slots a frozen model without extra keys or private attributes always holds None in
_UNSET_SLOTS = frozenset({"__pydantic_extra__", "__pydantic_private__"})


class PrimaryModel(BaseModel):
    """Frozen, no unknown keys; user construction fails with EncodeError."""

    model_config = ConfigDict(**WIRE_MODEL_CONFIG)  # (wire/model_types.py says why each key)
    NAME: ClassVar[str] = "primary"

    def __init__(self, **data: Any) -> None:
        try:
            super().__init__(**data)
        except ValidationError as exc:
            raise encode_error(exc, type(self).NAME, type(self)) from None

    def __getattr__(self, item: str) -> Any:
        """Decoded models leave pydantic's bookkeeping slots unset (see fast_models): their values here."""
        if item == "__pydantic_fields_set__":
            return set(type(self).model_fields)
        if item in _UNSET_SLOTS:
            return None
        return super().__getattr__(item)  # type: ignore[misc]


class PrimaryGroup(PrimaryModel):
    """A repeated or conditional block inside a sub-package (e.g. one joint)."""


class PrimaryPart(PrimaryModel):
    """A sub-package or a tagged message: the compatibility rule lives here.

    extra: bytes after the known layout (newer firmware appended fields).
    missing: names of layout fields absent because the part was shorter (older firmware).
    """

    FAMILY: ClassVar[str]
    TYPE: ClassVar[int]

    extra: bytes = b""
    missing: tuple[str, ...] = ()

    def values(self) -> dict[str, Any]:
        """Field values by spec name, without the bookkeeping fields."""
        return {k: getattr(self, k) for k in type(self).model_fields if k not in ("extra", "missing")}


class UnknownSubPackage(PrimaryModel):
    """A Robot State sub-package of a type the spec does not describe, kept whole."""

    NAME: ClassVar[str] = "unknown_subpackage"
    type: int
    size: int
    raw: bytes


class UnknownMessage(PrimaryModel):
    """A message of a type the spec does not describe, kept whole (header included)."""

    NAME: ClassVar[str] = "unknown_message"
    type: int
    size: int
    raw: bytes


class UnknownMember(PrimaryModel):
    """A tagged message (e.g. a Robot Message) whose sub-type the spec does not know."""

    NAME: ClassVar[str] = "unknown_member"
    family: str
    type: int
    prefix: dict[str, Any]
    raw: bytes


class OpaqueMessage(PrimaryModel):
    """A message whose layout is not documented (Modbus info): its body as bytes."""

    NAME: ClassVar[str] = "opaque_message"
    family: str
    type: int
    raw: bytes


class RobotStateMessage(PrimaryModel):
    """Robot State (type 16): its sub-packages in wire order."""

    NAME: ClassVar[str] = "robot_state"
    sub_packages: list[Any]

    def get(self, name: str) -> Any:
        """The first sub-package of that spec name (e.g. "joint_data"), or None."""
        for sub in self.sub_packages:
            if getattr(sub, "NAME", None) == name:
                return sub
        return None

    def __getitem__(self, name: str) -> Any:
        found = self.get(name)
        if found is None:
            raise KeyError(name)
        return found
