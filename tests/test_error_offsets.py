"""Error offsets point into the bytes given (issue 21.1): a 61-byte payload never gets 'offset 64'."""

from __future__ import annotations

import pytest

from rtde_spec.errors import DecodeError
from rtde_spec.examples import ur_rtde_default_outputs
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec

RECIPES = [
    ["timestamp", "actual_q", "robot_mode", "runtime_state"],  # 64 bytes: 61 reported offset 64
    ["timestamp", "actual_q", "robot_mode"],
    ur_rtde_default_outputs(),
]


@pytest.mark.parametrize("names", RECIPES, ids=lambda n: f"{len(n)}fields")
def test_every_wrong_length_payload_is_refused_at_an_offset_inside_it(names: list[str]) -> None:
    codec = RecipeCodec.for_names(names, "output")
    for length in [*range(0, codec.size + 9, 1 if codec.size < 100 else 7), 61, codec.size - 1]:
        if length == codec.size:
            continue
        for decode in (codec.decode, codec.decode_record, codec.decode_model):
            with pytest.raises(DecodeError) as info:
                decode(bytes(length))
            assert info.value.offset is not None and 0 <= info.value.offset <= length, (length, info.value)


def test_the_61_byte_payload_names_the_field_it_cuts_where_it_is() -> None:
    codec = RecipeCodec.for_names(RECIPES[0], "output")
    with pytest.raises(DecodeError) as info:
        codec.decode_record(bytes(61))
    assert (info.value.field, info.value.offset) == ("runtime_state", 60)
    assert "byte offset 60" in str(info.value) and "offset 64" not in str(info.value)


def test_offsets_of_a_payload_inside_a_buffer_count_from_the_buffer() -> None:
    codec = RecipeCodec.for_names(RECIPES[1], "output")
    package = codec.encode_package({"timestamp": 1.0, "actual_q": (0.0,) * 6, "robot_mode": 7}, 1)
    short = package[:30]
    with pytest.raises(DecodeError) as info:
        codec.decode_record(short, PAYLOAD_OFFSET)
    assert (info.value.field, info.value.offset) == ("actual_q", PAYLOAD_OFFSET + 8)
    with pytest.raises(DecodeError) as info:
        codec.decode(package + b"\0", PAYLOAD_OFFSET)
    assert info.value.offset == len(package)  # the first byte too many
