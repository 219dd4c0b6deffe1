"""bytes <-> RTDE package models, for every package type, protocol version and sender.

Decoding runs the one layout engine (`wire.layout`, shared with the primary
interface) once per package; truncation, bad length prefixes and non-ASCII text
are reported with field and byte offset. Nothing below raises anything but
RtdeSpecError. The construct structs are the readable, public definition.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any, Literal

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.rtde.layouts import layouts
from rtde_spec.rtde.messages import RtdeMessage
from rtde_spec.rtde.protocol_state import INITIAL_VERSION, ProtocolState
from rtde_spec.wire.framing import PackageFramer, check_header

Sender = Literal["controller", "client"]
_HEADER = struct.Struct(gen.HEADER_FORMAT)
_TYPE_AT = struct.calcsize(gen.HEADER_FORMAT[0] + gen.HEADER_FORMAT[1])  # the type follows the size
_BY_NAME: dict[str, type[RtdeMessage]] = {cls.NAME: cls for cls in gen.MESSAGES}


def _type_text(code: int) -> str:
    char = chr(code) if 32 <= code < 127 else "?"
    return f"{code} ({char!r})"


def message_class(package_type: int, sender: str, protocol_version: int) -> type[RtdeMessage]:
    """The model of a package type as sent by `sender` in a protocol version."""
    if sender not in gen.SENDERS:
        raise DecodeError(f"unknown sender {sender!r}", expected=" or ".join(gen.SENDERS))
    if protocol_version not in gen.PROTOCOLS:
        raise DecodeError(
            f"unknown protocol version {protocol_version}",
            expected=" or ".join(map(str, gen.PROTOCOLS)),
        )
    cls = gen.BY_KEY.get((package_type, sender, protocol_version))
    if cls is not None:
        return cls
    if package_type not in gen.PACKAGE_TYPES:
        known = ", ".join(_type_text(c) for c in gen.PACKAGE_TYPES)
        raise DecodeError(
            f"unknown package type {_type_text(package_type)}",
            field="type",
            offset=_TYPE_AT,
            expected=known,
            actual=package_type,
        )
    raise DecodeError(
        f"{gen.PACKAGE_TYPES[package_type]} is never sent by the {sender} in protocol {protocol_version}",
        field="type",
        offset=_TYPE_AT,
    )


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
    try:
        values, missing, stop = layouts()[cls.NAME].decode(body, 0, len(body))
    except DecodeError as exc:
        raise exc.relocated(gen.HEADER_SIZE, package=cls.NAME) from None
    if missing:
        raise DecodeError(
            "package ends inside this field",
            package=cls.NAME,
            field=missing[0],
            offset=gen.HEADER_SIZE + stop,
            expected=f"field{'s' if len(missing) > 1 else ''} {', '.join(missing)}",
            actual=f"{len(body) - stop} bytes left",
        )
    if strict and stop < len(body):
        raise DecodeError(
            f"{len(body) - stop} bytes after the last field",
            package=cls.NAME,
            offset=gen.HEADER_SIZE + stop,
            expected=f"package size {gen.HEADER_SIZE + stop}",
            actual=f"package size {gen.HEADER_SIZE + len(body)}",
        )
    try:
        return cls(**values)
    except EncodeError as exc:  # a value the model refuses (unreachable for bytes the engine accepted)
        raise DecodeError(f"does not decode: {exc.reason}", package=cls.NAME, field=exc.field) from None


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
    buf = bytes(data)
    size, ptype = check_header(
        buf, _HEADER, what="package", strict=strict, hint="; use decode_stream for several"
    )
    cls = message_class(ptype, sender, protocol_version)
    return decode_body(cls, buf[gen.HEADER_SIZE : size], strict=strict)


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
    if isinstance(message, gen.RequestProtocolVersion):
        state.on_request(message.protocol_version)
    elif isinstance(message, gen.RequestProtocolVersionReply):
        state.on_reply(message.accepted)


def setup_names(names: list[str]) -> list[str]:
    """The variables a setup request asks for: a trailing comma's empty last name is not one.

    ur_rtde ends its name lists with a comma; controllers answer types for the real
    names only. The model keeps the empty name so the package round-trips.
    """
    return names[:-1] if names and names[-1] == "" else names


def encode(message: RtdeMessage) -> bytes:
    """The whole package of a model, header included."""
    return message.to_bytes()


def build(name: str, **fields: Any) -> bytes:
    """Encode a package from its spec name and field values, e.g. build("start")."""
    return encode(message_by_name(name)(**fields))
