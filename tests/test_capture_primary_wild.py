"""`capture` of primary/secondary connections as real controllers' bytes look.

Byte patterns from real controllers published in public repositories, rebuilt here by hand
with struct (their bytes are not copied):

- python-urx's tools/packet.bin (SintefManufacturing/python-urx, commit ddbd6e9c, 2013): one
  Robot State a 1.x (CB2) controller sent on port 30002. Its Robot Mode Data is 29 bytes and its
  Masterboard Data uses 16-bit digital I/O words: the layouts before 3.0 the spec keeps as
  `older`. Before, `capture` never used the Version message, so a capture of such a robot was
  decoded with the newest layouts even when its Version message (1.8) was in the file: control
  mode 63 (the first byte of the speed fraction), analog inputs of 1e-188, a 48 V supply read as
  0.7 V, exit 0 and nothing said. Without the Version message (a capture started after the
  connection's first message) the same happened; the summary now says why the values may be
  wrong.
- A CB3 3.3.1 controller's first bytes on port 30002, posted on UR's forum ("How to read a tool
  analog input over TCP/IP?"): its Version message, then a Robot Message of a type (12) no
  document describes. It landed in `primary_unknown_member` as its raw bytes only: which family,
  which type and when were gone, so rows of different unknown messages could not be told apart.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.cli.main import main

from .capture_files import Conversation, write

MINUS_ONE = (1 << 64) - 1  # the timestamp a Version message carries


def version_message(major: int, minor: int, bugfix: int, build: int, date: bytes) -> bytes:
    """A Robot Message (20) of sub-type Version (3), packed as the document lays it out."""
    name = b"URControl"
    body = struct.pack(">QbB", MINUS_ONE, -2, 3) + bytes([len(name)]) + name
    body += struct.pack(">BBii", major, minor, bugfix, build) + date
    return struct.pack(">IB", 5 + len(body), 20) + body


def sub_package(sub_type: int, body: bytes) -> bytes:
    return struct.pack(">IB", 5 + len(body), sub_type) + body


def cb2_robot_state() -> bytes:
    """A Robot State in the layouts before 3.0: Robot Mode Data without the control mode (29
    bytes), Masterboard Data with 16-bit I/O words and two bytes after the safety state (on/off
    state, no Euromap67), then Joint Data in the layout that did not change."""
    robot_mode = struct.pack(">Q7?Bd", 57_918, True, True, True, False, False, False, False, 0, 1.0)
    joint = struct.pack(">dddffffB", -0.5, -0.5, 0.0, 0.25, 47.5, 24.5, 48.5, 253)
    masterboard = struct.pack(
        ">hhBBddBBddffffB", 3, 5, 0, 0, 0.001, 0.0, 0, 0, 0.0, 0.0, 23.5, 48.1, 0.7, 0.004, 8
    ) + bytes([1, 0])
    body = sub_package(0, robot_mode) + sub_package(1, joint * 6) + sub_package(3, masterboard)
    return struct.pack(">IB", 5 + len(body), 16) + body


def secondary(messages: list[bytes], robot: str = "192.168.1.8") -> Conversation:
    conv = Conversation(("192.168.1.100", 40003), (robot, 30002))
    conv.handshake()
    for message in messages:
        conv.send("server", message, dt=0.1)
    return conv


def test_the_version_message_picks_the_layouts_before_3_0(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    messages = [version_message(1, 8, 14035, 0, b"Oct 1 2013"), *[cb2_robot_state()] * 3]
    cap = write(tmp_path / "cb2.pcap", [secondary(messages)])
    tables = capture_tables(cap)
    modes = tables["primary_robot_mode_data"].to_pylist()
    assert len(modes) == 3
    assert {m["target_speed_fraction"] for m in modes} == {1.0}
    assert {m["control_mode"] for m in modes} == {None}  # 1.x sends none
    board = tables["primary_masterboard_data"].to_pylist()[-1]
    assert (board["digital_input_bits"], board["digital_output_bits"]) == (3, 5)
    assert board["analog_input0"] == 0.001
    assert board["robot_voltage_48v"] == pytest.approx(48.1)
    assert board["safety_mode"] == 8
    assert tables["primary_joint_data"].to_pylist()[0]["joints_5_q_actual"] == -0.5
    assert main(["capture", str(cap), "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    assert "controller 1.8.14035 is outside the spec's product lines" in err  # said once, not per message
    assert err.count("outside the spec's product lines") == 1  # once, in the summary (stdout: the connection)
    # the older layouts fit: the two bytes after the 1.x Masterboard Data's safety state are documented
    assert "layouts disagree" not in err


def test_without_the_version_message_the_summary_says_the_values_may_be_wrong(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cap = write(tmp_path / "mid.pcap", [secondary([cb2_robot_state()] * 3)])
    assert main(["capture", str(cap), "-o", str(tmp_path / "out")]) == 0  # not damage: the bytes are whole
    err = capsys.readouterr().err
    assert "layouts disagree" in err
    assert "no Version message before it in the capture" in err
    current = write(tmp_path / "current.pcap", [secondary([version_message(5, 8, 0, 0, b"x")])])
    assert main(["capture", str(current), "-o", str(tmp_path / "out2")]) == 0
    assert "layouts disagree" not in capsys.readouterr().err


def test_an_unknown_robot_message_keeps_its_family_type_and_prefix(tmp_path: Path) -> None:
    date = b"Jul 08 2016, 16:07:20"
    unknown = struct.pack(">QbB", MINUS_ONE, -2, 12) + struct.pack(">iiB", 489, 239, 1)
    messages = [version_message(3, 3, 1, 60, date), struct.pack(">IB", 5 + len(unknown), 20) + unknown]
    tables = capture_tables(write(tmp_path / "cb3.pcap", [secondary(messages, "10.8.64.249")]))
    (version,) = tables["primary_version_message"].to_pylist()
    assert (version["major_version"], version["minor_version"], version["bugfix_version"]) == (3, 3, 1)
    assert version["build_date"] == date.decode()
    (row,) = tables["primary_unknown_member"].to_pylist()
    assert (row["family"], row["type"]) == ("robot_message", 12)
    assert json.loads(row["prefix"]) == {"timestamp": MINUS_ONE, "source": -2, "robot_message_type": 12}
    assert row["raw"] == struct.pack(">iiB", 489, 239, 1).hex()


def test_parts_read_with_their_older_layout_are_not_a_disagreement() -> None:
    """Before, every Robot State of a 1.x controller was also flagged "layouts disagree": the
    fields an older layout lacks counted as "shorter" and the bytes the 1.x Masterboard Data sends
    after its documented end as "longer", though both are what that firmware sends."""
    from rtde_spec import PrimaryStreamDecoder

    decoder = PrimaryStreamDecoder()
    (_, _), (_, state) = decoder.feed(version_message(1, 8, 14035, 0, b"Oct 1 2013") + cb2_robot_state())
    (warning,) = decoder.warnings_for(state)
    assert "outside the spec's product lines" in warning
    unversioned = PrimaryStreamDecoder()
    (_, state) = unversioned.feed(cb2_robot_state())[0]
    assert any("layouts disagree" in w for w in unversioned.warnings_for(state))  # the newest do not fit


def test_a_sub_package_of_a_newer_firmware_keeps_its_type(tmp_path: Path) -> None:
    """A Robot State sub-package of a type the spec does not list yet (what a newer PolyScope adds)."""
    newer = sub_package(99, b"\x01\x02\x03")
    state = cb2_robot_state()
    state = struct.pack(">I", len(state) + len(newer)) + state[4:] + newer
    tables = capture_tables(write(tmp_path / "newer.pcap", [secondary([state])]))
    (row,) = tables["primary_unknown_subpackage"].to_pylist()
    assert (row["type"], row["size"], row["raw"]) == (99, 8, newer.hex())


def test_a_dump_of_one_message_decodes_with_the_version_given() -> None:
    """python-urx's packet.bin is one Robot State without the Version message that came before it:
    `decode_message` took no version, so through the public API it could only be read with the
    newest layouts (control mode 63, a 0.7 V supply)."""
    from rtde_spec import decode_message

    mode, _, board = decode_message(cb2_robot_state(), version="1.8").sub_packages
    assert (mode.target_speed_fraction, mode.control_mode) == (1.0, None)
    assert board.robot_voltage_48v == pytest.approx(48.1)
    assert decode_message(cb2_robot_state()).sub_packages[0].control_mode == 63  # the newest layouts


def test_controller_given_reads_a_capture_started_after_the_version_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A capture started late (no Version message) of a CB2: `--controller 1.8` picks its layouts,
    as `--recipe` stands in for an RTDE setup the capture missed; without it the summary says how."""
    cap = write(tmp_path / "late.pcap", [secondary([cb2_robot_state()] * 3)])
    assert main(["capture", str(cap), "-o", str(tmp_path / "plain")]) == 0
    assert "capture --controller VERSION gives the robot's" in capsys.readouterr().err
    assert main(["capture", str(cap), "-o", str(tmp_path / "out"), "--controller", "1.8"]) == 0
    err = capsys.readouterr().err
    assert "layouts disagree" not in err and "no Version message" not in err
    tables = capture_tables(cap, controller="1.8")
    board = tables["primary_masterboard_data"].to_pylist()[-1]
    assert board["robot_voltage_48v"] == pytest.approx(48.1)
    assert {m["control_mode"] for m in tables["primary_robot_mode_data"].to_pylist()} == {None}


def test_a_version_message_in_the_capture_wins_over_the_controller_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    messages = [version_message(1, 8, 14035, 0, b"Oct 1 2013"), cb2_robot_state()]
    cap = write(tmp_path / "cb2.pcap", [secondary(messages)])
    assert main(["capture", str(cap), "-o", str(tmp_path / "out"), "--controller", "5.15.0"]) == 0
    assert (
        "its Version message says 1.8.14035, --controller said 5.15.0: 1.8.14035 used"
        in capsys.readouterr().err
    )
    board = capture_tables(cap, controller="5.15.0")["primary_masterboard_data"].to_pylist()[-1]
    assert board["robot_voltage_48v"] == pytest.approx(48.1)


def _supply(out: str) -> list[float]:
    """The masterboard's 48 V supply in each Robot State `decode --format jsonl` printed."""
    rows = [json.loads(line) for line in out.splitlines()]
    subs = [sub for row in rows for sub in row.get("sub_packages", [])]
    return [sub["robot_voltage_48v"] for sub in subs if sub["package"] == "masterboard_data"]


def test_decode_of_a_dump_takes_the_controller_version(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    dump = tmp_path / "packet.bin"
    dump.write_bytes(cb2_robot_state())
    args = ["decode", "--protocol", "primary", str(dump), "--format", "jsonl"]
    assert main([*args, "--controller", "1.8"]) == 0
    assert _supply(capsys.readouterr().out) == [pytest.approx(48.1)]
    assert main(args) == 0
    assert _supply(capsys.readouterr().out) != [pytest.approx(48.1)]  # the newest layouts misread it
    assert main(["decode", str(dump), "--controller", "1.8"]) == 2  # RTDE has no per-version layouts
    assert "add --protocol primary" in capsys.readouterr().err
    with pytest.raises(SystemExit) as usage:
        main(["capture", str(dump), "-o", str(tmp_path / "o"), "--controller", "one"])
    assert usage.value.code == 2
    assert "is not a controller version" in capsys.readouterr().err


def test_primary_bytes_on_the_real_time_port_name_the_port_map(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The forum post's CB3 3.3.1 session is labelled port 30003 but holds primary bytes (its
    Version message first): the summary said only that the bytes hold no real-time message."""
    date = b"Jul 08 2016, 16:07:20"
    conv = Conversation(("10.8.64.1", 40003), ("10.8.64.249", 30003))
    conv.handshake()
    for message in [version_message(3, 3, 1, 60, date), *[cb2_robot_state()] * 40]:
        conv.send("server", message, dt=0.1)
    cap = write(tmp_path / "forum.pcap", [conv])
    assert main(["capture", str(cap), "-o", str(tmp_path / "out")]) == 3
    assert "they look like the primary interface: --port-map 30003=primary" in capsys.readouterr().err
    mapped = ["capture", str(cap), "-o", str(tmp_path / "mapped"), "--port-map", "30003=primary"]
    assert main(mapped) == 0
    assert capture_tables(cap, port_map={30003: "primary"})["primary_version_message"].num_rows == 1


def test_decode_says_a_part_that_fits_no_layout_and_how_to_give_the_version(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """python-urx's packet.bin read with the newest layouts: each misread part was labelled both
    "missing, older firmware" and "extra bytes, newer firmware", and nothing said how to fix it."""
    dump = tmp_path / "packet.bin"
    dump.write_bytes(cb2_robot_state())
    assert main(["decode", "--protocol", "primary", str(dump)]) == 0
    out = capsys.readouterr().out
    assert "(not this layout: missing target_speed_fraction" in out
    assert "older firmware" not in out and "newer firmware" not in out
    assert "no Version message in the input before it: --controller VERSION gives the robot's" in out
    assert main(["decode", "--protocol", "primary", str(dump), "--controller", "1.8"]) == 0
    out = capsys.readouterr().out
    assert "(missing, older firmware: control_mode" in out
    assert "controller version (from --controller): 1.8.0" in out
    assert "--controller VERSION gives" not in out
