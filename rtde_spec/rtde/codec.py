"""bytes <-> RTDE package models, for every package type, protocol version and sender.

Decoding runs the one layout engine (`wire.layout`, shared with the primary
interface) once per package; truncation, bad length prefixes and non-ASCII text
are reported with field and byte offset. Nothing below raises anything but
RtdeSpecError. The construct structs are the readable, public definition.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.rtde.packages import (  # noqa: F401 (Sender, setup_names: re-exported)
    Sender,
    decode_package,
    decode_values,
    observe_package,
    package_name,
    setup_names,
)
from rtde_spec.rtde.protocol_state import INITIAL_VERSION, ProtocolState
from rtde_spec.wire.framing import PackageFramer
from rtde_spec.wire.rtde_messages import RtdeMessage

_HEADER = struct.Struct(gen.HEADER_FORMAT)
_BY_NAME: dict[str, type[RtdeMessage]] = {cls.NAME: cls for cls in gen.MESSAGES}


def message_class(package_type: int, sender: str, protocol_version: int) -> type[RtdeMessage]:
    """The model of a package type as sent by `sender` in a protocol version."""
    return _BY_NAME[package_name(package_type, sender, protocol_version)]


def message_by_name(name: str) -> type[RtdeMessage]:
    """A package model by its spec name, e.g. "setup_outputs_v2"."""
    try:
        return _BY_NAME[name]
    except KeyError:
        raise EncodeError(f"unknown package {name!r}", expected=", ".join(_BY_NAME)) from None


def decode_body(cls: type[RtdeMessage], body: bytes, *, strict: bool = True) -> RtdeMessage:
    """The model of one package body (the bytes after the header), parsed once by the layout engine.

    Truncation, bad length prefixes and non-ASCII text are DecodeErrors with the
    field and the byte offset in the package.
    """
    return model_of(cls.NAME, decode_values(cls.NAME, body, strict=strict))


def model_of(name: str, values: dict[str, Any]) -> RtdeMessage:
    """The model of a package's decoded values."""
    cls = _BY_NAME[name]
    try:
        return cls(**values)
    except EncodeError as exc:  # a value the model refuses (unreachable for bytes the engine accepted)
        raise DecodeError(f"does not decode: {exc.reason}", package=name, field=exc.field) from None


def decode(
    data: bytes | bytearray | memoryview,
    *,
    protocol_version: int = 2,
    sender: Sender = "controller",
    strict: bool = True,
) -> RtdeMessage:
    """Decode exactly one package (header included).

    `sender` is who sent it ("controller" or "client"): the same type letter has
    different layouts in each direction. With strict=False, bytes after the last
    field and after the package are ignored instead of raising.
    """
    package = decode_package(data, protocol_version=protocol_version, sender=sender, strict=strict)
    return model_of(package.name, package.values)


def decode_stream(
    data: bytes | bytearray | memoryview,
    *,
    protocol_version: int | None = None,
    sender: Sender = "controller",
    strict: bool = True,
) -> Iterator[tuple[int, RtdeMessage]]:
    """(offset, model) for every package of a buffer of concatenated packages from one sender.

    The version follows `ProtocolState`: packages before a version exchange are
    protocol 1 when the stream starts with that exchange; otherwise (a stream that
    begins after the handshake) `protocol_version`, by default the newest.
    """
    framer = PackageFramer()
    packages = framer.feed(data)
    state = ProtocolState(one_sided=True)
    state.version = starting_version(packages[0][1] if packages else b"", protocol_version)
    for offset, package in packages:
        try:
            message = decode(package, protocol_version=state.version, sender=sender, strict=strict)
        except DecodeError as exc:
            raise exc.relocated(offset) from None
        observe(state, message)
        yield offset, message
    framer.close()


def starting_version(first_package: bytes, protocol_version: int | None) -> int:
    """Protocol 1 if the stream opens with the version exchange, else the given or newest version."""
    if protocol_version is not None:
        return protocol_version
    version_type = gen.RequestProtocolVersion.PACKAGE_TYPE
    if len(first_package) >= gen.HEADER_SIZE and _HEADER.unpack_from(first_package)[1] == version_type:
        return INITIAL_VERSION
    return max(gen.PROTOCOLS)


def observe(state: ProtocolState, message: RtdeMessage) -> None:
    """Move the protocol state on a version request or reply."""
    observe_package(state, message.NAME, message.fields())


def encode(message: RtdeMessage) -> bytes:
    """The whole package of a model, header included."""
    return message.to_bytes()


def build(name: str, **fields: Any) -> bytes:
    """Encode a package from its spec name and field values, e.g. build("start")."""
    return encode(message_by_name(name)(**fields))
