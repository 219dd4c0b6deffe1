"""Issue 18, point 3: capture keeps every decodable package after every TCP gap.

Captures are written frame by frame with dpkt (tests/capture_files.py); a lost
segment is one left out of the file, as when the capture tool drops it.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from rtde_spec import RecipeCodec, build
from rtde_spec.capture.decoder import capture_tables, decode_to_directory

from ..capture_files import (
    SMALL,
    Conversation,
    packages_touched,
    rtde_capture,
    rtde_packages,
    rtde_setup,
    write,
)
from ..helpers import ROOT

sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS

UR_RTDE = tuple(UR_RTDE_DEFAULT_OUTPUTS)  # 58 fields, 1,180-byte packages


def stamps(tables: dict, table: str = "rtde_outputs_1") -> list[int]:  # type: ignore[type-arg]
    return [round(t / 0.002) for t in tables[table].column("timestamp").to_pylist()]


def test_two_gaps_late_in_a_stream_keep_all_4998_packages(tmp_path: Path) -> None:
    """The issue's figure: a 5,000-package stream, two frames dropped, the second late:
    4,591 of 4,998 rows before (everything after the second gap lost)."""
    packages = rtde_packages(5000)
    path = rtde_capture(tmp_path / "two.pcap", packages, lost={1000, 4593})
    summary = decode_to_directory(path, tmp_path / "out")
    assert summary.tables["rtde_outputs_1"] == 4998
    (conn,) = summary.connections
    assert conn.gaps == 2 and conn.lost_bytes == 2 * len(packages[0])
    assert conn.skipped_bytes == 0 and conn.cut_packages == 0  # each gap is exactly one package
    assert stamps(capture_tables(path)) == [i for i in range(5000) if i not in (1000, 4593)]


@pytest.mark.parametrize("names", [SMALL, UR_RTDE], ids=["64-byte", "1180-byte"])
def test_four_lost_frames_cost_exactly_four_packages(tmp_path: Path, names: tuple[str, ...]) -> None:
    """One package per frame, four frames lost: 2,996 of 2,996 decodable kept (2,977 before)."""
    packages = rtde_packages(3000, names)
    lost = {400, 1100, 1101, 2999 - 3}  # two of them back to back
    path = rtde_capture(tmp_path / "four.pcap", packages, lost=lost, names=names)
    tables = capture_tables(path)
    assert stamps(tables) == [i for i in range(3000) if i not in lost]
    summary = decode_to_directory(path, tmp_path / "out")
    assert summary.connections[0].gaps == 3  # 1100 and 1101 are one hole
    assert summary.connections[0].lost_bytes == 4 * len(packages[0])


@pytest.mark.parametrize("names", [SMALL, UR_RTDE], ids=["64-byte", "1180-byte"])
def test_four_lost_700_byte_segments_lose_only_the_packages_they_touch(
    tmp_path: Path, names: tuple[str, ...]
) -> None:
    """Packages spanning segments, four 700-byte segments lost: every package that shares no
    byte with a lost segment is kept (500 of 3,000 before)."""
    packages = rtde_packages(3000, names)
    segments = len(b"".join(packages)) // 700
    lost = {segments // 5, 2 * segments // 5, 3 * segments // 5 + 1, 4 * segments // 5}
    path = rtde_capture(tmp_path / "spans.pcap", packages, lost=lost, names=names, segment=700)
    touched = packages_touched(packages, 700, lost)
    assert 4 <= len(touched) <= 4 * (700 // len(packages[0]) + 2)
    assert stamps(capture_tables(path)) == [i for i in range(3000) if i not in touched]
    (conn,) = decode_to_directory(path, tmp_path / "out").connections
    assert conn.gaps == 4 and conn.lost_bytes == 4 * 700
    # the bytes of touched packages that were captured are what the framing skipped
    assert conn.skipped_bytes == sum(len(packages[i]) for i in touched) - 4 * 700


def test_a_value_repeated_in_every_package_is_not_taken_for_a_header(tmp_path: Path) -> None:
    """Packages 64..66 hold the double 65.5 (40 50 60 ..) after a zero byte: `00 40 50` reads as
    a 64-byte pause reply, at the same place in every package, so each such header is
    confirmed by the next. Only a recipe's data package (its id and size) is trusted first."""
    packages = rtde_packages(3000)
    assert bytes.fromhex("004050") in packages[65]
    lost = {5, 10, 11}  # the hole at segment 5 ends inside package 65
    path = rtde_capture(tmp_path / "repeat.pcap", packages, lost=lost, segment=700)
    summary = decode_to_directory(path, tmp_path / "out")
    touched = packages_touched(packages, 700, lost)
    assert summary.tables["rtde_outputs_1"] == 3000 - len(touched) == 2965
    assert not summary.connections[0].errors  # no package taken for a pause reply
    assert stamps(capture_tables(path)) == [i for i in range(3000) if i not in touched]


def test_gaps_in_both_directions_and_on_primary_connections(tmp_path: Path) -> None:
    """Any number of gaps, anywhere: the client's input packages, the controller's outputs and
    a primary connection's robot state, each with holes."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    inputs = ("input_int_register_24", "speed_slider_fraction")
    conv.send("client", build("setup_inputs", variable_names=list(inputs)))
    conv.send("server", build("setup_inputs_reply", input_recipe_id=1, variable_types=["INT32", "DOUBLE"]))
    codec = RecipeCodec.for_names(list(inputs), "input")
    outputs = rtde_packages(600)
    for i in range(600):
        conv.send("server", outputs[i], keep=i % 97 != 5)  # 6 holes
        if i % 3 == 0:
            package = codec.encode_package({"input_int_register_24": i, "speed_slider_fraction": 0.5}, 1)
            conv.send("client", package, keep=i % 51 != 3)  # 4 holes
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from ur5e_robot_state import ur5e_robot_state_bytes

    primary = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 30001))
    primary.handshake()
    state = ur5e_robot_state_bytes()
    for k in range(40):
        primary.send("server", state[:700], dt=0.05, keep=k not in (7, 20))  # the first half lost
        primary.send("server", state[700:], dt=0.0, keep=k != 30)  # the second half lost
    tables = capture_tables(write(tmp_path / "both.pcap", [conv, primary]))
    assert stamps(tables) == [i for i in range(600) if i % 97 != 5]
    got = tables["rtde_inputs_1"].column("input_int_register_24").to_pylist()
    assert got == [i for i in range(0, 600, 3) if i % 51 != 3]
    assert tables["primary_joint_data"].num_rows == 40 - 3


def test_a_message_held_back_after_a_gap_keeps_the_time_of_its_own_segment(tmp_path: Path) -> None:
    """After a gap, a text message is only trusted once the robot state after it confirms it;
    its row still carries the capture time of the segment that brought it."""
    from rtde_spec._generated import primary_models as pm
    from rtde_spec.primary.codec import default_codec

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from ur5e_robot_state import ur5e_robot_state_bytes

    state = ur5e_robot_state_bytes()
    text = default_codec().encode(
        pm.TextMessage(timestamp=5, source=-2, robot_message_type=0, text_message="hi")
    )
    conv = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 30001))
    conv.handshake()
    conv.send("server", state, dt=0.1)
    conv.send("server", state[:300], dt=0.1, keep=False)  # lost: the next segment starts mid-message
    conv.send("server", state[300:] + text, dt=0.1)
    text_time = conv.time
    conv.send("server", state, dt=0.5)
    tables = capture_tables(write(tmp_path / "held.pcap", [conv]))
    assert tables["primary_text_message"].column("capture_time").to_pylist() == [pytest.approx(text_time)]
    assert tables["primary_joint_data"].num_rows == 2


def test_a_late_retransmission_within_the_hole_time_out_fills_the_hole(tmp_path: Path) -> None:
    """A segment lost on the wire is retransmitted later (after the retransmission time-out):
    its packages are kept, in order, and no gap is counted."""
    packages = rtde_packages(300)
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    held = []
    for i, package in enumerate(packages):
        _, frame = conv.send("server", package, keep=i not in (100, 101))
        if i in (100, 101):
            held.append(frame)
        if i == 200:  # 0.2 s after the loss
            for frame in held:
                conv.resend(frame)
    summary = decode_to_directory(write(tmp_path / "late.pcap", [conv]), tmp_path / "out")
    assert summary.connections[0].gaps == 0 and summary.tables["rtde_outputs_1"] == 300
    assert not summary.damage()


def test_cli_reports_the_gaps_and_exits_3_unless_lenient(tmp_path: Path) -> None:
    from ..capture_files import run_capture

    path = rtde_capture(tmp_path / "gaps.pcap", rtde_packages(500), lost={100, 300})
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert "rtde_outputs_1 (498 rows)" in result.stdout
    assert "2 gaps (128 bytes lost)" in result.stderr and str(path) in result.stderr
    lenient = run_capture(str(path), "-o", str(tmp_path / "out"), "--lenient", cwd=tmp_path)
    assert lenient.returncode == 0 and "2 gaps (128 bytes lost)" in lenient.stderr
