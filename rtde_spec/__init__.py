"""Universal Robots' RTDE and primary/secondary interfaces, from one declarative spec.

Everything the README shows imports from here or from a public subpackage
(`rtde_spec.rtde.models`, `rtde_spec.rtde.structs`, `rtde_spec.primary.models`,
`rtde_spec.primary.structs`). Names load on first use, so `import rtde_spec` and
`from rtde_spec import RecipeCodec` stay fast. Errors derive from `RtdeSpecError`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

_EXPORTS: dict[str, str] = {
    # RTDE packages, sessions and streams
    "decode": "rtde_spec.rtde.codec",
    "decode_stream": "rtde_spec.rtde.codec",
    "encode": "rtde_spec.rtde.codec",
    "build": "rtde_spec.rtde.codec",
    "message_class": "rtde_spec.rtde.codec",
    "RtdeMessage": "rtde_spec.wire.rtde_messages",
    "ProtocolState": "rtde_spec.rtde.protocol_state",
    "SessionDecoder": "rtde_spec.rtde.session",
    "StreamDecoder": "rtde_spec.rtde.stream",
    # recipes
    "Recipe": "rtde_spec.recipes.model",
    "RecipeCodec": "rtde_spec.recipes.codec",
    "load_recipes": "rtde_spec.recipes.files",
    "save_recipes": "rtde_spec.recipes.files",
    "validate_recipes": "rtde_spec.recipes.validation",
    # primary / secondary interfaces
    "PrimaryStreamDecoder": "rtde_spec.primary.codec",
    "decode_message": "rtde_spec.primary.codec",
    "encode_message": "rtde_spec.primary.codec",
    # the spec
    "Catalogue": "rtde_spec.metamodel.catalogue",
    "Version": "rtde_spec.metamodel.versions",
    # output
    "open_writer": "rtde_spec.output.writers",
    "to_pandas": "rtde_spec.output.tables",
    "to_arrow": "rtde_spec.output.tables",
    # errors
    "RtdeSpecError": "rtde_spec.errors",
    "DecodeError": "rtde_spec.errors",
    "EncodeError": "rtde_spec.errors",
    "RecipeError": "rtde_spec.errors",
    "ProtocolError": "rtde_spec.errors",
    "SpecError": "rtde_spec.errors",
    "UsageError": "rtde_spec.errors",
    "RtdeConnectionError": "rtde_spec.errors",
    # transport
    "RtdeClient": "rtde_spec.rtde.client",
    "AsyncRtdeClient": "rtde_spec.rtde.aio",
    "PrimaryClient": "rtde_spec.primary.client",
    "Emulator": "rtde_spec.emulator.server",
    "EmulatorThread": "rtde_spec.emulator.server",
    "EmulatorProcess": "rtde_spec.emulator.server",
    "EmulatorConfig": "rtde_spec.emulator.server",
}

__all__ = [
    "AsyncRtdeClient",
    "Catalogue",
    "DecodeError",
    "Emulator",
    "EmulatorConfig",
    "EmulatorProcess",
    "EmulatorThread",
    "EncodeError",
    "PrimaryClient",
    "PrimaryStreamDecoder",
    "ProtocolError",
    "ProtocolState",
    "Recipe",
    "RecipeCodec",
    "RecipeError",
    "RtdeClient",
    "RtdeConnectionError",
    "RtdeMessage",
    "RtdeSpecError",
    "SessionDecoder",
    "SpecError",
    "StreamDecoder",
    "UsageError",
    "Version",
    "__version__",
    "build",
    "decode",
    "decode_message",
    "decode_stream",
    "encode",
    "encode_message",
    "load_recipes",
    "message_class",
    "open_writer",
    "save_recipes",
    "to_arrow",
    "to_pandas",
    "validate_recipes",
]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'rtde_spec' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)


if TYPE_CHECKING:
    from rtde_spec.emulator.server import Emulator, EmulatorConfig, EmulatorProcess, EmulatorThread
    from rtde_spec.errors import (
        DecodeError,
        EncodeError,
        ProtocolError,
        RecipeError,
        RtdeConnectionError,
        RtdeSpecError,
        SpecError,
        UsageError,
    )
    from rtde_spec.metamodel.catalogue import Catalogue
    from rtde_spec.metamodel.versions import Version
    from rtde_spec.output.tables import to_arrow, to_pandas
    from rtde_spec.output.writers import open_writer
    from rtde_spec.primary.client import PrimaryClient
    from rtde_spec.primary.codec import PrimaryStreamDecoder, decode_message, encode_message
    from rtde_spec.recipes.codec import RecipeCodec
    from rtde_spec.recipes.files import load_recipes, save_recipes
    from rtde_spec.recipes.model import Recipe
    from rtde_spec.recipes.validation import validate_recipes
    from rtde_spec.rtde.aio import AsyncRtdeClient
    from rtde_spec.rtde.client import RtdeClient
    from rtde_spec.rtde.codec import build, decode, decode_stream, encode, message_class
    from rtde_spec.rtde.protocol_state import ProtocolState
    from rtde_spec.rtde.session import SessionDecoder
    from rtde_spec.rtde.stream import StreamDecoder
    from rtde_spec.wire.rtde_messages import RtdeMessage
