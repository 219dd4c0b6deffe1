"""Data packages sent without their recipe id byte, turned into the guides' form.

UR's guides put the recipe id in every data package; UR's C++ client library reads
protocol-1 output data packages without it (spec/rtde/packages.yaml `data_recipe_id`
names the sources). Where the spec says the id is optional, a decoder tells the two
forms apart by size: the recipe's payload plus the header is the form without the id,
one byte more the guides' form. Every decoder here (the live client, the stream
decoder, the session and capture decoders) turns the form without the id into the
guides' form first, with the implied recipe id, so everything after it reads one form.
"""

from __future__ import annotations

import struct

from rtde_spec._generated.constants import (
    DATA_PACKAGE_TYPE,
    DATA_SENT_WITHOUT_RECIPE_ID,
    DATA_WITHOUT_RECIPE_ID,
    RTDE_HEADER_FORMAT,
)

_HEADER = struct.Struct(RTDE_HEADER_FORMAT)
HEADER_SIZE = _HEADER.size
_TYPE_AT = struct.calcsize(RTDE_HEADER_FORMAT[:2])  # the type follows the size


def implied_recipe_id(sender: str, protocol_version: int) -> int | None:
    """The recipe id of `sender`'s data packages sent without one in this protocol; None when
    they always carry it."""
    return DATA_WITHOUT_RECIPE_ID.get((sender, protocol_version))


def lacks_recipe_id(package: bytes | bytearray | memoryview, payload_size: int | None) -> bool:
    """True when `package` is a data package exactly the header plus a payload of `payload_size`
    bytes long: the form without the recipe id (the guides' form is one byte longer)."""
    return (
        payload_size is not None
        and len(package) == HEADER_SIZE + payload_size
        and len(package) > _TYPE_AT
        and package[_TYPE_AT] == DATA_PACKAGE_TYPE
    )


def with_recipe_id(package: bytes | bytearray | memoryview, recipe_id: int) -> bytes:
    """The guides' form of a data package sent without its id: the id after the header, size + 1."""
    head = _HEADER.pack(len(package) + 1, DATA_PACKAGE_TYPE)
    return head + bytes((recipe_id,)) + bytes(package[HEADER_SIZE:])


def sent_without_recipe_id(sender: str, protocol_version: int) -> bool:
    """Whether a real `sender` sends its data packages without the id byte in this protocol
    (a controller in protocol 1): the form an emulator of that sender writes."""
    return (sender, protocol_version) in DATA_SENT_WITHOUT_RECIPE_ID


def without_recipe_id(package: bytes) -> bytes:
    """A data package in the guides' form with its id byte taken out: size - 1, then the payload."""
    return _HEADER.pack(len(package) - 1, DATA_PACKAGE_TYPE) + package[HEADER_SIZE + 1 :]
