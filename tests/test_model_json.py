"""Decoded models dump to JSON and back whatever their bytes hold.

Protocol bytes (a part's `extra`, an unknown or opaque message's `raw`, an RTDE data
package's payload) are rarely UTF-8, pydantic's default for bytes in JSON: a Robot State
from newer firmware, with appended fields, could not be dumped. They are hex in JSON.
"""

from __future__ import annotations

import json
import struct

import pytest

from rtde_spec import decode_message
from rtde_spec.rtde.codec import decode

BINARY = b"\xff\x00\x81\xfe"


@pytest.mark.parametrize(
    "data",
    [
        struct.pack(">IB", 5 + len(BINARY), 5) + BINARY,  # Modbus info: opaque
        struct.pack(">IB", 5 + len(BINARY), 99) + BINARY,  # an unknown message type
        struct.pack(">IBQbB", 15 + len(BINARY), 20, 7, -2, 200) + BINARY,  # an unknown robot message
        struct.pack(">IB", 15 + len(BINARY), 16)
        + struct.pack(">IB", 10 + len(BINARY), 250)
        + b"\x00" * 5
        + BINARY,  # an unknown sub-package
    ],
    ids=["opaque", "unknown-message", "unknown-member", "unknown-sub-package"],
)
def test_primary_messages_with_binary_bytes_dump_to_json_and_back(data: bytes) -> None:
    message = decode_message(data)
    dumped = message.model_dump_json()
    assert "ff0081fe" in dumped
    # a Robot State's sub-packages are typed Any: each comes back from its own class's JSON
    for model in getattr(message, "sub_packages", [message]):
        assert type(model).model_validate_json(model.model_dump_json()) == model


def test_a_part_with_binary_extra_bytes_dumps_to_json_and_back() -> None:
    text = struct.pack(">QbB", 1, -2, 0) + b"hi"
    message = decode_message(struct.pack(">IB", 5 + len(text), 20) + text)
    longer = message.model_copy(update={"extra": BINARY})
    assert json.loads(longer.model_dump_json())["extra"] == BINARY.hex()
    assert type(longer).model_validate_json(longer.model_dump_json()) == longer


def test_an_rtde_data_package_with_binary_payload_dumps_to_json_and_back() -> None:
    package = decode(struct.pack(">HBB", 4 + len(BINARY), ord("U"), 1) + BINARY)
    dumped = package.model_dump_json()
    assert BINARY.hex() in dumped
    assert type(package).model_validate_json(dumped) == package
