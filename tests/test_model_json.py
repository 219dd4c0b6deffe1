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


def _robot_message(kind: int, body: bytes) -> bytes:
    head = struct.pack(">QbB", 1000, -2, kind)
    return struct.pack(">IB", 5 + len(head) + len(body), 20) + head + body


NOT_UTF8 = b"caf\xe9 \xff!"  # Latin-1 text, as an old controller or a script may send


def test_text_that_is_not_utf8_dumps_to_json_escaped_and_encodes_back_to_its_bytes() -> None:
    """The decoder keeps bytes that are not UTF-8 (surrogate escapes), which pydantic's JSON
    refuses: the dump failed. JSON now shows them as \\xNN; Python values and encoding keep them."""
    from rtde_spec.primary.codec import default_codec

    data = _robot_message(0, NOT_UTF8)
    message = decode_message(data)
    assert json.loads(message.model_dump_json())["text_message"] == "caf\\xe9 \\xff!"
    assert message.model_dump()["text_message"] == NOT_UTF8.decode("utf-8", "surrogateescape")
    assert default_codec().encode(message) == data
    good = decode_message(_robot_message(0, "café".encode()))
    assert json.loads(good.model_dump_json())["text_message"] == "café"  # UTF-8 text is untouched


def test_a_none_global_variable_value_sets_the_fields_a_validated_one_sets() -> None:
    from rtde_spec.primary.codec import default_codec
    from rtde_spec.wire.primary_values import VariableValue

    values = default_codec().values
    code, _ = values.by_name["NONE"]
    shared = values.decode_all(struct.pack(">BB", code, values.separator), 0, 2, "values")[0]
    assert shared.type == "NONE" and shared.value is None
    twin = VariableValue.model_validate(shared.model_dump())
    assert shared.model_fields_set == twin.model_fields_set == {"type", "value"}
    assert shared.model_dump(exclude_unset=True) == twin.model_dump(exclude_unset=True)


FRESH = """
import sys
import pydantic_core
from pydantic import TypeAdapter
from rtde_spec import decode_message
message = decode_message(bytes.fromhex(sys.argv[1]))
assert pydantic_core.to_json(message)
assert TypeAdapter(list).dump_json([message])
print("ok")
"""


@pytest.mark.parametrize(
    "data",
    [
        struct.pack(">IB", 5 + len(BINARY), 5) + BINARY,
        struct.pack(">IB", 5 + len(BINARY), 99) + BINARY,
        struct.pack(">IBQbB", 15 + len(BINARY), 20, 7, -2, 200) + BINARY,
        _robot_message(0, b"hi"),
        bytes.fromhex(
            "00000034100000002f00000000000001e2400101010000010007003ff0000000000000"
            "3fe00000000000003ff000000000000000"
        ),
    ],
    ids=["opaque", "unknown-message", "unknown-member", "text", "robot-state"],
)
def test_pydantic_serializes_decoded_messages_in_a_fresh_process(data: bytes) -> None:
    """Schemas are deferred until a class is validated, and decoded models never are: outside
    their own dump methods (pydantic_core.to_json, a TypeAdapter, a parent model) pydantic-core
    met a placeholder serializer. The decoders' set-up now builds each class's schema."""
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-c", FRESH, data.hex()], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


def test_nan_and_infinities_dump_to_json_and_read_back() -> None:
    """pydantic writes NaN and infinities as `null` by default: a decoded model holding one (an
    unset value, a controller's NaN) dumped to JSON that its own class refused to read back. They
    are now the strings "NaN", "Infinity", "-Infinity": valid JSON that validates back."""
    import math

    from rtde_spec import RecipeCodec
    from rtde_spec._generated import primary_models as pm
    from rtde_spec._generated import rtde_models as rm
    from rtde_spec.primary.codec import encode_message
    from rtde_spec.wire.primary_base import RobotStateMessage

    names = [n for n in pm.CartesianInfo.model_fields if n not in ("extra", "missing")]
    values = {**dict.fromkeys(names, 0.5), "x": math.nan, "rz": -math.inf}
    message = decode_message(encode_message(RobotStateMessage(sub_packages=[pm.CartesianInfo(**values)])))
    codec = RecipeCodec.for_names(["timestamp", "actual_q"], "output")
    record = codec.decode_model(codec.encode({"timestamp": math.nan, "actual_q": (math.inf,) * 6}))
    setup = rm.SetupOutputsV2(output_frequency=math.nan, variable_names=["timestamp"])
    for model in (message.sub_packages[0], record, setup):
        dumped = model.model_dump_json()
        assert "null" not in dumped and '"NaN"' in dumped
        again = type(model).model_validate_json(dumped)
        assert json.loads(again.model_dump_json()) == json.loads(dumped)  # (NaN != NaN: as JSON)
    assert math.isinf(type(record).model_validate_json(record.model_dump_json()).actual_q[0])
