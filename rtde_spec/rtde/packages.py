"""RTDE packages as a spec name and a dict of values: decoded and encoded by the layout engine alone.

The capture decoder and the clients' control path (version, setup, start, pause
and their replies) need a package's name and values, not its pydantic model;
loading the ~100 model classes, and pydantic with them, is most of a command's
start-up. This module reads the generated constants and layouts only. The models
(`rtde.codec`) are built from what it decodes, when a caller asks for one.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any, Literal

from rtde_spec._generated.constants import (
    RTDE_HEADER_FORMAT,
    RTDE_LIMITS,
    RTDE_PACKAGE_TYPES,
    RTDE_PACKAGES,
    RTDE_PROTOCOLS,
    RTDE_SENDERS,
)
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.rtde.protocol_state import ProtocolState
from rtde_spec.wire.framing import as_bytes, check_header
from rtde_spec.wire.rtde_layouts import layouts

Sender = Literal["controller", "client"]
HEADER = struct.Struct(RTDE_HEADER_FORMAT)
HEADER_SIZE = HEADER.size
TYPE_AT = struct.calcsize(RTDE_HEADER_FORMAT[:2])  # the type follows the size
MAX_SIZE = RTDE_LIMITS["package_max_bytes"]
TYPE_OF: dict[str, int] = {name: key[0] for key, name in RTDE_PACKAGES.items()}
"""Spec name of a layout -> its package type code."""

# the layouts the decoders act on, by their spec names (a test holds them to the spec)
DATA = "data_package"
TEXTS = frozenset({"text_message", "text_message_v1_controller", "text_message_v1_client"})
SETUP_REQUESTS = {"setup_outputs_v1": "output", "setup_outputs_v2": "output", "setup_inputs": "input"}
SETUP_REPLIES = {
    "setup_outputs_v1_reply": "output",
    "setup_outputs_v2_reply": "output",
    "setup_inputs_reply": "input",
}
VERSION_REQUEST, VERSION_REPLY = "request_protocol_version", "request_protocol_version_reply"
CONTROLLER_VERSION_REPLY = "get_urcontrol_version_reply"


@dataclass(frozen=True)
class Package:
    """One decoded package: its layout's spec name, type code and field values in wire order.

    Fields read as attributes too (`reply.accepted`), as on the models;
    `rtde.codec.model_of(name, values)` makes the model.
    """

    name: str
    package_type: int
    values: dict[str, Any]

    def __getattr__(self, field: str) -> Any:
        try:
            return self.__dict__["values"][field]
        except KeyError:
            raise AttributeError(f"{self.__dict__.get('name', 'package')} has no field {field!r}") from None

    def fields(self) -> dict[str, Any]:
        return self.values


def _type_text(code: int) -> str:
    char = chr(code) if 32 <= code < 127 else "?"
    return f"{code} ({char!r})"


def package_name(package_type: int, sender: str, protocol_version: int) -> str:
    """The spec name of the layout of a package type as sent by `sender` in a protocol version."""
    if sender not in RTDE_SENDERS:
        raise DecodeError(f"unknown sender {sender!r}", expected=" or ".join(RTDE_SENDERS))
    if protocol_version not in RTDE_PROTOCOLS:
        raise DecodeError(
            f"unknown protocol version {protocol_version}",
            expected=" or ".join(map(str, RTDE_PROTOCOLS)),
        )
    name = RTDE_PACKAGES.get((package_type, sender, protocol_version))
    if name is not None:
        return name
    if package_type not in RTDE_PACKAGE_TYPES:
        known = ", ".join(_type_text(c) for c in RTDE_PACKAGE_TYPES)
        raise DecodeError(
            f"unknown package type {_type_text(package_type)}",
            field="type",
            offset=TYPE_AT,
            expected=known,
            actual=package_type,
        )
    raise DecodeError(
        f"{RTDE_PACKAGE_TYPES[package_type]} is never sent by the {sender} in protocol {protocol_version}",
        field="type",
        offset=TYPE_AT,
    )


def decode_values(name: str, body: bytes, *, strict: bool = True) -> dict[str, Any]:
    """The field values of one package body (the bytes after the header), parsed once.

    Truncation, bad length prefixes and non-ASCII text are DecodeErrors with the
    field and the byte offset in the package.
    """
    try:
        values, missing, stop = layouts()[name].decode(body, 0, len(body))
    except DecodeError as exc:
        raise exc.relocated(HEADER_SIZE, package=name) from None
    if missing:
        raise DecodeError(
            "package ends inside this field",
            package=name,
            field=missing[0],
            offset=HEADER_SIZE + stop,
            expected=f"field{'s' if len(missing) > 1 else ''} {', '.join(missing)}",
            actual=f"{len(body) - stop} bytes left",
        )
    if strict and stop < len(body):
        raise DecodeError(
            f"{len(body) - stop} bytes after the last field",
            package=name,
            offset=HEADER_SIZE + stop,
            expected=f"package size {HEADER_SIZE + stop}",
            actual=f"package size {HEADER_SIZE + len(body)}",
        )
    return values


def decode_package(
    data: bytes | bytearray | memoryview,
    *,
    protocol_version: int = 2,
    sender: str = "controller",
    strict: bool = True,
) -> Package:
    """Decode exactly one package (header included) to its name and values."""
    buf = as_bytes(data, "decode")
    size, ptype = check_header(
        buf, HEADER, what="package", strict=strict, hint="; use decode_stream for several"
    )
    name = package_name(ptype, sender, protocol_version)
    return Package(name, ptype, decode_values(name, buf[HEADER_SIZE:size], strict=strict))


def encode_package(name: str, values: dict[str, Any]) -> bytes:
    """The whole package of a layout and its values, header included.

    For packages this library builds from checked values (a client's requests); what
    a user types goes through the models, which check every value first.
    """
    try:
        body = layouts()[name].encode(values)
    except EncodeError as exc:
        raise exc.relocated(package=name) from None
    size = HEADER_SIZE + len(body)
    if size > MAX_SIZE:
        raise EncodeError(
            "package too large for the size field",
            package=name,
            field="size",
            expected=f"<= {MAX_SIZE} bytes",
            actual=f"{size} bytes",
        )
    return HEADER.pack(size, TYPE_OF[name]) + body


def observe_package(state: ProtocolState, name: str, values: dict[str, Any]) -> None:
    """Move the protocol state on a version request or reply."""
    if name == VERSION_REQUEST:
        state.on_request(values["protocol_version"])
    elif name == VERSION_REPLY:
        state.on_reply(values["accepted"])


def setup_names(names: list[str]) -> list[str]:
    """The variables a setup request asks for: a trailing comma's empty last name is not one.

    ur_rtde ends its name lists with a comma; controllers answer types for the real
    names only. The model keeps the empty name so the package round-trips.
    """
    return names[:-1] if names and names[-1] == "" else names
