"""URCL's external-control records decoded from the spec: bytes packed here with `struct` as
UR's client library packs them (big-endian int32 words, floats times MULT_JOINTSTATE)."""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import pytest

from rtde_spec.errors import DecodeError, EncodeError, SpecError
from rtde_spec.external.codec import record_codec
from rtde_spec.metamodel.external import load_external

from .helpers import ROOT


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def test_a_servoj_reverse_message_gives_radians_and_seconds() -> None:
    codec = record_codec("reverse", "reverse_command")
    plan, values = codec.decode(words(20, 1_000_000, -2_500_000, 3_141_593, 0, 1, -1, 1))
    assert plan.name == "motion_target" and plan.table == "urcl_reverse"
    assert values == {
        "read_timeout": 0.02,
        "target": (1.0, -2.5, 3.141593, 0.0, 1e-06, -1e-06),
        "control_mode": 1,
    }
    assert codec.size == 32


def test_the_control_mode_word_picks_the_reading_of_the_six_words() -> None:
    codec = record_codec("reverse", "reverse_command")
    plan, values = codec.decode(words(200, -1, 12, 0, 0, 0, 0, 3))
    assert plan.name == "trajectory_control"
    assert (values["trajectory_action"], values["point_count"], values["read_timeout"]) == (-1, 12, 0.2)
    plan, values = codec.decode(words(200, 1, 0, 0, 0, 0, 0, 6))
    assert (plan.name, values["freedrive_action"]) == ("freedrive_control", 1)
    plan, _ = codec.decode(words(100, 0, 0, 0, 0, 0, 0, -2))  # MODE_STOPPED: the default reading
    assert plan.name == "motion_target"


def test_trajectory_points_motion_primitive_and_spline() -> None:
    codec = record_codec("trajectory", "trajectory_point")
    q = [500_000, -1_000_000, 1_000_000, 0, 1_500_000, 250_000]
    plan, values = codec.decode(words(*q, *[0] * 6, 1_050_000, 1_400_000, 0, 0, 0, 0, 2_000_000, 50_000, 1))
    assert plan.name == "motion_primitive"
    assert values["target"] == (0.5, -1.0, 1.0, 0.0, 1.5, 0.25)
    assert (values["velocity"], values["duration"], values["blend_radius"], values["motion_type"]) == (
        1.05, 2.0, 0.05, 1,
    )  # fmt: skip
    plan, values = codec.decode(words(*q, *q, *q, 500_000, 1, 51))
    assert (plan.name, values["spline_type"], values["duration"]) == ("spline_point", 1, 0.5)
    assert values["velocities"] == values["positions"]


def test_older_trajectory_layouts_by_name() -> None:
    nine = record_codec("trajectory", "trajectory_point", "cartesian_flag_9")
    assert nine.size == 36
    _, values = nine.decode(words(1, 2, 3, 4, 5, 6, 1500, 20, 1))
    assert (values["duration"], values["blend_radius"], values["cartesian"]) == (1.5, 0.02, 1)
    with pytest.raises(KeyError, match="cartesian_flag_9"):
        record_codec("trajectory", "trajectory_point", "no_such_layout")


def test_script_commands_each_with_their_arguments() -> None:
    codec = record_codec("script_command", "script_command")
    plan, values = codec.decode(words(1, 1_500_000, 0, 0, 50_000, *[0] * 23))
    assert plan.name == "set_payload"
    assert values == {"command": 1, "mass": 1.5, "cog": (0.0, 0.0, 0.05)}
    plan, values = codec.decode(words(7, 1, *[0] * 26))
    assert (plan.name, values["enabled"]) == ("set_friction_compensation", 1)  # a flag, not scaled
    plan, values = codec.decode(words(99, *range(27)))
    assert plan.name == "unknown_command" and values["words"] == tuple(range(27))


def test_results_from_the_robot() -> None:
    assert record_codec("trajectory", "trajectory_result").decode(words(2))[1] == {"result": 2}
    assert record_codec("script_command", "tool_contact_result").decode(words(0))[1] == {"result": 0}


def test_encode_scales_rounds_and_pads_the_record() -> None:
    codec = record_codec("script_command", "script_command")
    raw = codec.encode("set_payload", {"command": 1, "mass": 1.2345678, "cog": (0.1, -0.2, 0.3)})
    assert raw == words(1, 1_234_568, 100_000, -200_000, 300_000, *[0] * 23)
    with pytest.raises(EncodeError):
        codec.encode("set_payload", {"command": 1, "mass": 1.0})
    with pytest.raises(EncodeError):
        codec.encode("set_payload", {"command": 1, "mass": float("nan"), "cog": (0, 0, 0)})


def test_a_cut_record_and_plausibility() -> None:
    codec = record_codec("reverse", "reverse_command")
    with pytest.raises(DecodeError) as info:
        codec.decode(words(20, 1, 2))
    assert info.value.expected == "32 bytes"
    assert codec.plausible(words(20, 0, 0, 0, 0, 0, 0, 5))
    assert not codec.plausible(words(20, 0, 0, 0, 0, 0, 0, 77))  # no such control mode


def spec_copy(tmp_path: Path) -> Path:
    root = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", root)
    return root


def test_the_spec_refuses_a_selector_at_another_offset(tmp_path: Path) -> None:
    root = spec_copy(tmp_path)
    path = root / "external_control" / "protocols.yaml"
    text = path.read_text()
    text = text.replace(
        "- {name: freedrive_action, type: int32, enum: FreedriveControlMessage}\n"
        "              - {name: unused, type: int32, count: 5}",
        "- {name: freedrive_action, type: int32, enum: FreedriveControlMessage}\n"
        "              - {name: unused, type: int32, count: 4}",
    )
    path.write_text(text)
    with pytest.raises(SpecError, match="not at the same offset"):
        load_external(root)


def test_the_spec_refuses_scale_on_text_and_unknown_types(tmp_path: Path) -> None:
    root = spec_copy(tmp_path)
    path = root / "external_control" / "protocols.yaml"
    text = path.read_text().replace(
        "{name: result, type: int32, enum: TrajectoryResult}", "{name: result, type: int24}"
    )
    path.write_text(text)
    with pytest.raises(SpecError, match="no primitive"):
        load_external(root)
    path.write_text(
        text.replace("{name: result, type: int24}", "{name: result, type: string, length: rest, scale: 2}")
    )
    with pytest.raises(SpecError, match="scale is for numbers"):
        load_external(root)


def test_an_unknown_protocol_is_a_key_error_naming_the_known_ones() -> None:
    """record_codec("nope", ...) raised a bare StopIteration (which a generator turns into
    RuntimeError); like an unknown message or layout, it is a KeyError that lists the names."""
    with pytest.raises(KeyError, match=r"no external-control protocol nope \(known: reverse, "):
        record_codec("nope", "reverse_command")


def test_a_record_s_codec_names_a_bad_offset_and_the_missing_fields() -> None:
    """A negative offset raised a bare struct.error; a record with values missing was refused
    without naming which."""
    codec = record_codec("reverse", "reverse_command")
    for at in (-4, codec.size + 1):
        with pytest.raises(DecodeError, match="offset outside the buffer") as info:
            codec.decode(bytes(codec.size), at)
        assert info.value.offset == at
    with pytest.raises(EncodeError, match="missing: target, control_mode"):
        codec.encode("motion_target", {"read_timeout": 1.0})
