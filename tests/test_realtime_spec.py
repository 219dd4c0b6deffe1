"""The real-time interface (port 30003) as the spec describes it, against bytes packed by hand.

The messages here are packed with plain struct from the guide's table (Realtime Client
Interface, RealTime 5.9/5.10: every value a double, its "Gnuplot col." numbering the
doubles from 1), each double set to its column number, so a field decoded from the
wrong offset shows at once. Sizes per version are the ones the guide and ur_modern_driver
give (3.0-3.1 1044, 3.2-3.4 1060, 3.5+ 1108, 3.10 and 5.4 1116, 5.9 1140, 5.10 1220).
"""

from __future__ import annotations

import math
import random
import re
import shutil
import struct
from pathlib import Path

import pytest

from rtde_spec.errors import DecodeError, EncodeError, SpecError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.realtime import load_realtime
from rtde_spec.metamodel.versions import Version
from rtde_spec.realtime import RealtimeStream, decode, encode, layout_for

from .helpers import ROOT

# (name in the guide, number of doubles) in the guide's order, up to 5.10
GUIDE = [
    ("Time", 1), ("q target", 6), ("qd target", 6), ("qdd target", 6), ("I target", 6),
    ("M target", 6), ("q actual", 6), ("qd actual", 6), ("I actual", 6), ("I control", 6),
    ("Tool vector actual", 6), ("TCP speed actual", 6), ("TCP force", 6), ("Tool vector target", 6),
    ("TCP speed target", 6), ("Digital input bits", 1), ("Motor temperatures", 6),
    ("Controller Timer", 1), ("Test value", 1), ("Robot Mode", 1), ("Joint Modes", 6),
    ("Safety Mode", 1), ("empty", 6), ("Tool Accelerometer values", 3), ("empty", 6),
    ("Speed scaling", 1), ("Linear momentum norm", 1), ("SoftwareOnly", 1), ("SoftwareOnly2", 1),
    ("V main", 1), ("V robot", 1), ("I robot", 1), ("V actual", 6), ("Digital outputs", 1),
    ("Program state", 1), ("Elbow position", 3), ("Elbow velocity", 3), ("Safety Status", 1),
    ("Unused", 3), ("Payload Mass", 1), ("Payload CoG", 3), ("Payload Inertia", 6),
]  # fmt: skip
SIZES = {"3.0.0": 1044, "3.1.0": 1044, "3.2.0": 1060, "3.4.0": 1060, "3.5.0": 1108, "3.9.0": 1108,
         "3.10.0": 1116, "3.15.0": 1116, "5.0.0": 1108, "5.3.0": 1108, "5.4.0": 1116, "5.8.0": 1116,
         "5.9.0": 1140, "5.10.0": 1220, "5.25.0": 1220}  # fmt: skip


def hand_packed(size: int) -> bytes:
    """A message of `size` bytes, every double holding its gnuplot column number (1, 2, ...)."""
    doubles = (size - 4) // 8
    return struct.pack(f">i{doubles}d", size, *(float(c) for c in range(1, doubles + 1)))


def columns(name: str) -> tuple[float, ...]:
    """The column numbers of a field of the guide's table."""
    at = 1
    for entry, count in GUIDE:
        if entry == name:
            return tuple(float(c) for c in range(at, at + count))
        at += count
    raise KeyError(name)


@pytest.mark.parametrize(("version", "size"), SIZES.items())
def test_each_version_sends_the_documented_size(version: str, size: int) -> None:
    assert layout_for(version).size == size
    assert len(encode({}, version)) == size


@pytest.mark.parametrize("version", ["3.1.0", "3.4.0", "3.15.0", "5.3.0", "5.9.0", "5.10.0"])
def test_every_field_decodes_from_the_guides_column(version: str) -> None:
    values = decode(hand_packed(SIZES[version]), version, strict=True)
    assert values["message_size"] == SIZES[version]
    assert values["time"] == 1.0
    assert values["q_target"] == columns("q target") == tuple(range(2, 8))
    assert values["q_actual"] == columns("q actual") == tuple(range(32, 38))
    assert values["tcp_force"] == columns("TCP force")
    assert values["tool_vector_actual"] == columns("Tool vector actual")
    assert values["tool_vector_target"] == columns("Tool vector target")
    assert values["motor_temperatures"] == columns("Motor temperatures")
    assert values["robot_mode"] == 95 and isinstance(values["robot_mode"], int)  # guide: col 95
    assert values["joint_modes"] == tuple(range(96, 102))
    assert values["safety_mode"] == 102
    assert values["tool_accelerometer_values"] == columns("Tool Accelerometer values")
    assert values["speed_scaling"] == columns("Speed scaling")[0]
    assert values["v_actual"] == columns("V actual")
    v = Version.parse(version)
    if v >= Version(3, 2):
        assert values["program_state"] == 132  # python-ur-control reads it at double 131 (0-based)
    if v >= Version(5, 4) or Version(3, 10) <= v < Version(4):
        assert values["safety_status"] == columns("Safety Status")[0]
    if version == "5.10.0":
        assert values["payload_mass"] == columns("Payload Mass")[0]
        assert values["payload_cog"] == columns("Payload CoG")
        assert values["payload_inertia"] == columns("Payload Inertia")
        assert "missing" not in values and "extra_bytes" not in values
    if version in ("3.1.0", "3.4.0"):
        assert "elbow_position" not in values


def test_without_a_version_the_size_picks_the_layout() -> None:
    assert "payload_mass" in decode(hand_packed(1220))
    assert "safety_status" in decode(hand_packed(1116)) and "reserved_5" not in decode(hand_packed(1116))
    assert decode(hand_packed(1060))["program_state"] == 132


def test_longer_and_shorter_messages_keep_what_they_have() -> None:
    longer = decode(hand_packed(1228), "5.10.0")  # newer firmware appended a double
    assert longer["extra_bytes"] == 8 and longer["payload_mass"] == columns("Payload Mass")[0]
    shorter = decode(hand_packed(1108), "5.10.0")  # an older layout
    assert shorter["missing"] == (
        "safety_status",
        "reserved_5",
        "payload_mass",
        "payload_cog",
        "payload_inertia",
    )
    with pytest.raises(DecodeError, match=r"expected 1220, got 1108"):
        decode(hand_packed(1108), "5.10.0", strict=True)


def test_damage_is_a_decode_error_with_its_place() -> None:
    message = bytearray(hand_packed(1116))
    with pytest.raises(DecodeError, match="cut short"):
        decode(bytes(message[:500]))
    with pytest.raises(DecodeError, match="cut short"):
        decode(b"\x00\x00")
    struct.pack_into(">d", message, layout_for("3.15.0").offset("robot_mode"), math.nan)
    with pytest.raises(DecodeError) as info:
        decode(bytes(message), "3.15.0")
    assert info.value.field == "robot_mode" and info.value.offset == 4 + 94 * 8
    with pytest.raises(DecodeError, match="impossible message size"):
        decode(struct.pack(">i", 1 << 30) + bytes(8))


def test_a_stream_in_any_chunks_gives_every_message_and_skips_a_bad_one() -> None:
    good = hand_packed(1220)
    bad = bytearray(good)
    struct.pack_into(">d", bad, layout_for("5.10.0").offset("safety_mode"), 2.5)
    data = good * 3 + bytes(bad) + good * 2
    rng = random.Random(7)
    stream = RealtimeStream("5.10.0")
    got = []
    at = 0
    while at < len(data):
        step = rng.randint(1, 700)
        got += stream.feed(data[at : at + step])
        at += step
    assert len(got) == 5 and stream.pending == 0
    assert all(m["q_actual"] == columns("q actual") for m in got)
    assert len(stream.errors) == 1 and "package #4" in str(stream.errors[0])
    assert stream.errors[0].offset == 3 * 1220 + layout_for("5.10.0").offset("safety_mode")


def test_a_stream_with_an_impossible_size_stops_before_buffering_it() -> None:
    stream = RealtimeStream()
    assert len(stream.feed(hand_packed(1116))) == 1
    with pytest.raises(DecodeError) as info:
        stream.feed(struct.pack(">i", 2_000_000_000))
    assert info.value.offset == 1116 and stream.pending <= 4


def test_values_survive_encode_and_decode() -> None:
    values = {
        "q_actual": (0.1, -1.2, 1.3, -1.4, -1.5, 0.6),
        "robot_mode": 7,
        "safety_status": 1,
        "time": 12.5,
    }
    out = decode(encode(values, "5.10.0"), "5.10.0", strict=True)
    assert {k: out[k] for k in values} == values


def spec_copy(tmp_path: Path) -> Path:
    shutil.copytree(ROOT / "spec", tmp_path / "spec")
    return tmp_path / "spec"


@pytest.mark.parametrize(
    ("values", "field", "reason"),
    [
        ({"q_actal": [0.1] * 6}, "q_actal", "not a field of any real-time layout: q_actal"),
        ({"robot_mode": 1.5}, "robot_mode", "not a whole number"),
        ({"safety_mode": math.nan}, "safety_mode", "not a whole number"),
        ({"time": "1"}, "time", "not a number (text is no number)"),
        ({"q_actual": [1, 2, 3, 4, 5, "6"]}, "q_actual", "not 6 numbers"),
    ],
)
def test_what_a_message_cannot_carry_is_refused_naming_the_field(
    values: dict, field: str, reason: str
) -> None:
    """A misspelt name was dropped (its field sent as zeros), text was taken as a number, and a
    mode of 1.5 was encoded into a message the decoder then refused."""
    with pytest.raises(EncodeError, match=re.escape(reason)) as info:
        encode(values, "5.10.0")
    assert info.value.field == field
    message = encode({"robot_mode": 7}, "5.10.0")
    assert encode(decode(message, "5.10.0"), "5.10.0") == message  # a decoded message encodes back


def test_the_spec_refuses_fields_that_do_not_add_up_to_the_documented_size(tmp_path: Path) -> None:
    root = spec_copy(tmp_path)
    path = root / "realtime/interface.yaml"
    path.write_text(path.read_text().replace("length: 1140", "length: 1148"))
    with pytest.raises(
        SpecError, match=r"lengths.6.*5.9.0: the fields add up to 1140 bytes, the sources give 1148"
    ):
        load_realtime(root, Catalogue.default())


def test_the_spec_refuses_an_unknown_rtde_name_and_a_group(tmp_path: Path) -> None:
    root = spec_copy(tmp_path)
    path = root / "realtime/interface.yaml"
    path.write_text(path.read_text().replace("rtde: target_qdd", "rtde: target_qddd"))
    with pytest.raises(SpecError, match="'target_qddd' is no RTDE output"):
        load_realtime(root, Catalogue.default())
    path.write_text(
        path.read_text().replace("type: double, count: 6, unit: A, rtde: target_current", "type: string")
    )
    with pytest.raises(SpecError, match="only double, int32, uint64 values"):
        load_realtime(root)


def test_bytes_after_one_message_are_refused_not_dropped() -> None:
    """`decode` of one message ignored what followed it: a recv() chunk holding a message and a
    half lost the half unsaid. It now says how many bytes follow, and where."""
    size = layout_for("5.9").size
    one = struct.pack(">I", size) + bytes(size - 4)
    assert decode(one)["message_size"] == len(one)
    with pytest.raises(DecodeError, match="10 bytes after the message") as info:
        decode(one + one[:10])
    assert info.value.offset == len(one)
