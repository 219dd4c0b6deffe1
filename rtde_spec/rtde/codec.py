"""bytes <-> RTDE package models, for every package type, protocol version and sender.

Decoding first walks the spec's layout over the bytes, so truncation, bad length
prefixes and non-ASCII text are reported with field and byte offset; only then
does the construct struct parse. Nothing below raises anything but RtdeSpecError.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any, Literal

from construct import ConstructError
from pydantic import ValidationError

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError, EncodeError
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


def _check_layout(cls: type[RtdeMessage], body: bytes, strict: bool) -> None:
    """Walk the spec layout over the body; raise DecodeError where it does not fit."""
    pos = 0
    for lay in cls.LAYOUT:
        at = gen.HEADER_SIZE + pos
        left = len(body) - pos
        if lay.kind in ("fixed", "prefixed") and left < lay.size:
            what = "length prefix" if lay.kind == "prefixed" else "field"
            raise DecodeError(
                f"package ends inside the {what}",
                package=cls.NAME,
                field=lay.name,
                offset=at,
                expected=f"{lay.size} bytes",
                actual=f"{left} bytes",
            )
        if lay.kind == "fixed":
            pos += lay.size
            continue
        if lay.kind == "prefixed":
            length = int.from_bytes(body[pos : pos + lay.size], "big")
            start = pos + lay.size
            if len(body) - start < length:
                raise DecodeError(
                    f"length prefix says {length} bytes but the package ends first",
                    package=cls.NAME,
                    field=lay.name,
                    offset=at,
                    expected=f"{length} bytes",
                    actual=f"{len(body) - start} bytes",
                )
            end = start + length
        else:
            start, end = pos, len(body)
        if lay.text:
            for i in range(start, end):
                if body[i] > 0x7F:
                    raise DecodeError(
                        "text is not ASCII",
                        package=cls.NAME,
                        field=lay.name,
                        offset=gen.HEADER_SIZE + i,
                        expected="bytes 0x00..0x7f",
                        actual=f"0x{body[i]:02x}",
                    )
        pos = end
    if strict and pos < len(body):
        raise DecodeError(
            f"{len(body) - pos} bytes after the last field",
            package=cls.NAME,
            offset=gen.HEADER_SIZE + pos,
            expected=f"package size {gen.HEADER_SIZE + pos}",
            actual=f"package size {gen.HEADER_SIZE + len(body)}",
        )


def decode_body(cls: type[RtdeMessage], body: bytes, *, strict: bool = True) -> RtdeMessage:
    """The model of one package body (the bytes after the header)."""
    _check_layout(cls, body, strict)
    try:
        parsed = cls.STRUCT.parse(body)
        values = {lay.name: parsed[lay.name] for lay in cls.LAYOUT}
        return cls(**values)
    except (ConstructError, ValidationError, EncodeError, UnicodeDecodeError) as exc:
        # unreachable when the layout walk above is right; never leak internals
        raise DecodeError(f"does not decode: {exc}", package=cls.NAME) from None


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
