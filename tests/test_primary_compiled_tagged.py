"""The generated decoders of tagged messages (robot messages, program state) against the general walk.

Each member's straight-line decoder (`primary/compiled_tagged.py`) must give the model the
layout walk gives, key for key and in the same order, on well-formed messages with bytes
after them, and must leave every cut-off or damaged message to the walk, which says what
is wrong: the two codecs below differ only in that one has no generated decoders.
"""

from __future__ import annotations

import json
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtde_spec._generated import primary_models as gen
from rtde_spec.errors import DecodeError
from rtde_spec.primary.codec import PrimaryCodec, default_codec, encode_message
from rtde_spec.wire.primary_base import PrimaryPart

from .budget import examples
from .primary_strategies import MEMBER_KEYS, member_strategy

TAGGED = ("robot_message", "program_state")  # the tagged families of the spec
TAGGED_KEYS = [key for key in MEMBER_KEYS if key[0] in TAGGED]


def _general() -> PrimaryCodec:
    codec = PrimaryCodec()
    for fam in codec.families.values():
        fam.fast.clear()
    return codec


GENERAL = _general()


def _family(name: str) -> Any:
    return next(f for f in default_codec().families.values() if f.spec.name == name)


def _outcome(codec: PrimaryCodec, data: bytes, strict: bool = True) -> Any:
    """The model and its dict's key order, or the error's text. As reprs: a damaged byte can make
    a NaN, which equals nothing, not even the same NaN the other decoder gives (seen once)."""
    try:
        message = codec.decode_message(data, strict=strict)
    except DecodeError as exc:
        return ("error", str(exc))
    return repr(message), list(message.__dict__), repr(message.model_dump())


def _json(model: Any) -> Any:
    """A model's values as its JSON gives them: NaN as "NaN", which equals itself."""
    return json.loads(model.model_dump_json())


def test_every_tagged_member_has_a_generated_decoder() -> None:
    """Text, version, safety mode, robot comm, key, request value, runtime exception, program
    threads and both global-variable messages: none is left to the general walk."""
    names = {f.spec.name for f in default_codec().families.values() if f.direct is not None}
    assert names == set(TAGGED)
    for key in TAGGED_KEYS:
        assert key[1] in _family(key[0]).fast, f"{key} has no generated decoder"
    assert len(TAGGED_KEYS) == 10


@pytest.mark.parametrize("key", TAGGED_KEYS, ids=[f"{f}-{t}" for f, t in TAGGED_KEYS])
def test_generated_tagged_decoder_equals_the_layout_walk(key: tuple[str, int]) -> None:
    codec = default_codec()
    fast = _family(key[0]).fast[key[1]]

    @settings(max_examples=examples(40), deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(member_strategy(*key), st.binary(max_size=6), st.integers(0, 300), st.data())
    def check(part: PrimaryPart, tail: bytes, cut: int, data: st.DataObject) -> None:
        whole = encode_message(part)
        made = fast(whole, 5, len(whole))  # the generated decoder itself, not the walk
        assert made is not None and (made == part or _json(made) == _json(part))  # (NaN equals nothing)
        assert _outcome(codec, whole) == _outcome(GENERAL, whole)
        grown = (len(whole) + len(tail)).to_bytes(4, "big") + whole[4:] + tail  # tail inside the message
        assert _outcome(codec, grown) == _outcome(GENERAL, grown)
        assert _outcome(codec, whole + tail, strict=False) == _outcome(GENERAL, whole + tail, strict=False)
        short = whole[: max(5, min(cut, len(whole)))]
        short = len(short).to_bytes(4, "big") + short[4:]  # a message cut inside its fields
        assert _outcome(codec, short) == _outcome(GENERAL, short)
        at = data.draw(st.integers(5, len(whole) - 1), label="damaged byte")
        damaged = whole[:at] + bytes([data.draw(st.integers(0, 255), label="value")]) + whole[at + 1 :]
        assert _outcome(codec, damaged) == _outcome(GENERAL, damaged)

    check()


def test_a_length_prefix_past_the_end_is_named_by_the_walk() -> None:
    """A key message whose title length runs past the end: the generated decoder steps aside
    and the error names the member, the field and the offset, as without it."""
    codec = default_codec()
    key_message = gen.MEMBERS[("robot_message", 7)]
    good = encode_message(
        key_message(
            timestamp=1,
            source=-2,
            robot_message_type=7,
            robot_message_code=3,
            robot_message_argument=4,
            robot_message_title="Title",
            key_text_message="text",
        )
    )
    title_at = 5 + 8 + 1 + 1 + 4 + 4  # header, timestamp, source, type, code, argument
    bad = good[:title_at] + b"\xff" + good[title_at + 1 :]
    with pytest.raises(DecodeError) as fast_error:
        codec.decode_message(bad)
    with pytest.raises(DecodeError) as walk_error:
        GENERAL.decode_message(bad)
    assert str(fast_error.value) == str(walk_error.value)
    assert "robot_message_title" in str(fast_error.value) and f"{title_at}" in str(fast_error.value)


def test_a_length_prefix_one_byte_past_the_end_is_an_error_not_a_short_text() -> None:
    """The last thread name of a program threads message claims one byte more than is left."""
    threads = gen.MEMBERS[("robot_message", 14)]
    thread = gen.GROUPS["ProgramThread"](label_id=1, label_name="a", thread_name="main")
    good = encode_message(threads(timestamp=1, source=-2, robot_message_type=14, threads=[thread]))
    at = len(good) - len(b"main") - 2  # the thread name's uint16 length
    assert good[at : at + 2] == b"\x00\x04"
    bad = good[:at] + b"\x00\x05" + good[at + 2 :]
    with pytest.raises(DecodeError, match="length prefix says 5 bytes") as error:
        default_codec().decode_message(bad)
    assert _outcome(GENERAL, bad) == ("error", str(error.value))


def test_unknown_and_opaque_messages_behave_as_validated_ones() -> None:
    """Unknown messages, unknown members, opaque messages and unknown sub-packages are built
    without validation too: equal to validated twins both ways, same dumps, fields set, copies."""
    import copy
    import pickle
    import struct

    codec = default_codec()
    unknown = struct.pack(">IB", 8, 99) + b"abc"
    modbus = struct.pack(">IB", 8, 5) + b"\x00\x01\x02"
    member = struct.pack(">IBQbB", 20, 20, 7, -2, 200) + b"hello"
    sub = struct.pack(">IB", 13, 16) + struct.pack(">IB", 8, 250) + b"xyz"
    for data in (unknown, modbus, member, sub):
        decoded = codec.decode_message(data)
        if hasattr(decoded, "sub_packages"):
            decoded = decoded.sub_packages[0]
        validated = type(decoded)(**dict(decoded))
        assert decoded == validated and validated == decoded
        assert decoded.model_dump() == validated.model_dump()
        assert decoded.model_fields_set == validated.model_fields_set
        assert list(decoded.__dict__) == list(validated.__dict__)
        assert pickle.loads(pickle.dumps(decoded)) == copy.deepcopy(decoded) == validated
    assert type(codec.decode_message(modbus)).__name__ == "OpaqueMessage"
    assert codec.decode_message(member).prefix["robot_message_type"] == 200


def test_decoded_global_variable_values_behave_as_validated_ones() -> None:
    """Decoded values leave pydantic's bookkeeping slots unset too: equality, fields set, dumps,
    copies and pickling match values built by validation, nested lists included."""
    import copy
    import pickle

    from rtde_spec.wire.primary_values import VariableValue

    update = gen.MEMBERS[("program_state", 1)]
    values = [
        VariableValue(type="NUM", value=1.5),
        VariableValue(type="INT", value=-3),
        VariableValue(type="POSE", value=(1.0, 2.0, 3.0, 0.5, 0.25, 0.0)),
        VariableValue(type="VAR_STRING", value="héllo"),
        VariableValue(
            type="LIST", value=[VariableValue(type="INT", value=1), VariableValue(type="NUM", value=2.0)]
        ),
    ]
    data = encode_message(update(timestamp=1, robot_message_type=1, start_index=0, variable_values=values))
    decoded = default_codec().decode_message(data).variable_values  # type: ignore[union-attr]
    assert decoded == values and values == decoded
    for got, want in zip(decoded, values, strict=True):
        assert got.model_fields_set == {"type", "value"}
        assert got.model_dump() == want.model_dump() and got.model_dump_json() == want.model_dump_json()
        assert pickle.loads(pickle.dumps(got)) == copy.deepcopy(got) == copy.copy(got) == want
        assert repr(got) == repr(want)
        with pytest.raises(AttributeError, match="no attribute 'nope'"):
            got.nope  # noqa: B018


def test_a_fresh_process_dumps_decoded_messages() -> None:
    """Decoded models are never validated, so their classes' schemas may be unbuilt when a
    Robot State (sub-packages typed Any) is dumped: in a process that has validated nothing,
    model_dump and model_dump_json of every kind of message work."""
    import subprocess
    import sys

    from .helpers import ROOT

    code = """
import json, sys
sys.path.insert(0, sys.argv[1])
from ur5e_robot_state import ur5e_robot_state_bytes
from rtde_spec import decode_message
message = decode_message(ur5e_robot_state_bytes())
dumped = message.model_dump()
assert dumped["sub_packages"][1]["joints"][5]["joint_mode"] == 253
assert json.loads(message.model_dump_json())["sub_packages"][0]["robot_mode"] == 7
print("ok")
"""
    done = subprocess.run(
        [sys.executable, "-c", code, str(ROOT / "benchmarks")], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]
