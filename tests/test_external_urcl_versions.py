"""URCL releases whose records the spec once read in another release's layout, captured as each
release sends them: the reverse interface's first word (a keepalive count to 1.3.3), the script
commands' length (5 words in 0.4.0 and 1.2.0-1.3.1, 26 in 1.3.2-1.4.0) and the trajectory points
of 2.10.0 and 2.11.0 (motion types in the older word order, durations in microseconds).

Each session is a real pcap file: the robot requests its program on 50002 and the driver sends a
program carrying the lines of that release's resources/external_control.urscript (copied from the
tag in UniversalRobots/Universal_Robots_Client_Library, the multipliers filled in as
src/ur/ur_driver.cpp does), then writes its records, packed here with `struct` as that release's
C++ packs them, one write per record. `rtde-spec capture` must name the release's layout, say it
read it from the program, and give back the values sent.
"""

from __future__ import annotations

import json
import math
import shutil
import struct
import subprocess
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.cli.wireshark_cmd import dissector_path
from rtde_spec.errors import SpecError
from rtde_spec.external.layouts import named_by
from rtde_spec.metamodel.external import external_spec, load_external

from .capture_files import Conversation, run_capture, write
from .helpers import ROOT

ROBOT, PC = "192.168.56.101", "192.168.56.1"
T0 = 1_700_000_000.0
MULT = 1_000_000  # ReverseInterface::MULT_JOINTSTATE in every release
Q = (0.1, -1.5, 1.2, -0.3, 1.57, 3.141593)
POSE = (0.5, 0.1, 0.3, 3.14, 0.0, 0.0)
VIA = (0.45, 0.2, 0.3, 3.14, 0.0, 0.0)

# Lines of resources/external_control.urscript at the tags, as they stand there
KEEPALIVE = ["global keepalive = -2", "keepalive = params_mult[1]", "    keepalive = params_mult[1]"]
READ_TIMEOUT = [
    "global read_timeout = 0.0 # First read is blocking",
    "    read_timeout = params_mult[1] / 1000.0 ",
]
POINTS_9 = ["TRAJECTORY_POINT_JOINT = 0", "TRAJECTORY_POINT_CARTESIAN = 1", "TRAJECTORY_DATA_DIMENSION = 7"]
POINTS_21 = [*POINTS_9[:2], "TRAJECTORY_POINT_JOINT_SPLINE = 2", "TRAJECTORY_DATA_DIMENSION = 3*6 + 1"]
MOTION = ["MOVEJ", "MOVEL", "MOVEP", "MOVEC", "OPTIMOVEJ", "OPTIMOVEL"]
MOTION_2_0 = [f"MOTION_TYPE_{name} = {i}" for i, name in enumerate(MOTION)]
MOTION_2_0 += ["MOTION_TYPE_SPLINE = 51", "TRAJECTORY_DATA_DIMENSION = 3 * 6 + 1"]
POSE_JOINT = ["MOVEJ_POSE", "MOVEL_JOINT", "MOVEP_JOINT", "MOVEC_JOINT", "MOVEC_JOINT_POSE",
              "MOVEC_POSE_JOINT", "OPTIMOVEJ_POSE", "OPTIMOVEL_JOINT"]  # fmt: skip
MOTION_2_12 = [f"MOTION_TYPE_{name} = {i}" for i, name in enumerate(MOTION + POSE_JOINT)]
MOTION_2_12 += ["MOTION_TYPE_SPLINE = 51", "TRAJECTORY_DATA_DIMENSION = 3 * 6 + 1"]
COMMANDS_3 = ["ZERO_FTSENSOR = 0", "SET_PAYLOAD = 1", "SET_TOOL_VOLTAGE = 2"]
COMMANDS_7 = [*COMMANDS_3, "START_FORCE_MODE = 3", "END_FORCE_MODE = 4", "START_TOOL_CONTACT = 5",
              "END_TOOL_CONTACT = 6"]  # fmt: skip
REVERSE_8 = "REVERSE_INTERFACE_DATA_DIMENSION = 8"


def dimension(words: int) -> str:
    return f"SCRIPT_COMMAND_DATA_DIMENSION = {words}"


OLDEST = (1000, [*POINTS_9, *COMMANDS_3, dimension(5), *KEEPALIVE])
SPLINES = (1000, [REVERSE_8, *POINTS_21, *COMMANDS_7, dimension(26), *KEEPALIVE])
WATCHDOG = (1000, [REVERSE_8, *POINTS_21, *COMMANDS_7, dimension(26), *READ_TIMEOUT])
MOTIONS = [REVERSE_8, *MOTION_2_0, *COMMANDS_7, dimension(28), *READ_TIMEOUT]
# tag -> (TrajectoryPointInterface::MULT_TIME, the program's lines)
RELEASES: dict[str, tuple[int, list[str]]] = {
    "0.4.0": OLDEST, "1.2.0": OLDEST, "1.3.1": OLDEST,
    "1.3.2": SPLINES, "1.3.3": SPLINES,
    "1.3.4": WATCHDOG, "1.4.0": WATCHDOG,
    "1.5.0": (1000, [REVERSE_8, *POINTS_21[:3], "TRAJECTORY_DATA_DIMENSION = 3 * 6 + 1", *COMMANDS_7,
                     dimension(28), *READ_TIMEOUT]),
    "2.9.0": (1000, MOTIONS),
    "2.10.0": (1_000_000, MOTIONS), "2.11.0": (1_000_000, MOTIONS),
    "2.12.0": (1_000_000, [REVERSE_8, *MOTION_2_12, *COMMANDS_7, dimension(28),
                           "global read_timeout = 0.0 # First read is blocking",
                           "    read_timeout = params_mult[1] / 1000.0"]),
}  # fmt: skip
# tag -> the layout its program names: (reverse command, trajectory point, script command)
NAMED = {
    "0.4.0": ("keepalive", "cartesian_flag_9", "words_5"),
    "1.2.0": ("keepalive", "cartesian_flag_9", "words_5"),
    "1.3.1": ("keepalive", "cartesian_flag_9", "words_5"),
    "1.3.2": ("keepalive", "point_type_21", "words_26"),
    "1.3.3": ("keepalive", "point_type_21", "words_26"),
    "1.3.4": ("read_timeout_ms", "point_type_21", "words_26"),
    "1.4.0": ("read_timeout_ms", "point_type_21", "words_26"),
    "1.5.0": ("read_timeout_ms", "point_type_21", "words_28"),
    "2.9.0": ("read_timeout_ms", "motion_type_ms", "words_28"),
    "2.10.0": ("read_timeout_ms", "motion_type_blocks_us", "words_28"),
    "2.11.0": ("read_timeout_ms", "motion_type_blocks_us", "words_28"),
    "2.12.0": ("read_timeout_ms", "motion_type_us", "words_28"),
}


def program(tag: str) -> bytes:
    """The release's program as its driver sends it: MULT_JOINTSTATE and MULT_TIME filled in."""
    mult_time, lines = RELEASES[tag]
    head = ["# HEADER_BEGIN", "", "steptime = get_steptime()", f"MULT_jointstate = {MULT}",
            f"MULT_time = {mult_time}", "", "#Constants", "MODE_FORWARD = 3"]  # fmt: skip
    body = [f"# line {i} of the program" for i in range(200)]
    return "\n".join([*head, *lines, "", *body, "# NODE_CONTROL_LOOP_ENDS", ""]).encode()


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def session(
    tmp_path: Path, tag: str, port: int, records: list[bytes], answers: tuple[bytes, ...] = ()
) -> Path:
    """A pcap of the program request on 50002, then `records` from the driver on `port` (one
    segment each) and the robot's `answers` there."""
    sender = Conversation((ROBOT, 40002), (PC, 50002), time=T0)
    sender.handshake()
    sender.send("client", b"request_program\n")
    text = program(tag)
    for i in range(0, len(text), 1400):
        sender.send("server", text[i : i + 1400], dt=0.0005)
    conv = Conversation((ROBOT, port - 10000), (PC, port), time=T0 + 1)
    conv.handshake()
    for record in records:
        conv.send("server", record, dt=0.004)
    for answer in answers:
        conv.send("client", answer, dt=0.5)
    return write(tmp_path / f"urcl_{tag}_{port}.pcap", [sender, conv])


def capture(tmp_path: Path, path: Path) -> tuple[dict[str, list[dict[str, Any]]], str]:
    """The tables `rtde-spec capture` wrote (JSON Lines rows by table, in capture order) and its stderr."""
    out = tmp_path / "out"
    done = run_capture(str(path), "-o", str(out), "--format", "jsonl", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    tables = {
        table.name: sorted(
            (json.loads(line) for f in table.rglob("*.jsonl") for line in f.read_text().splitlines()),
            key=lambda row: row["capture_time"],
        )
        for table in out.iterdir()
        if table.is_dir()
    }
    return tables, done.stderr


def sent(value: float, mult: int = MULT, rounded: bool = True) -> int:
    """A value as the C++ puts it in a word: round(value * mult), or static_cast's truncation."""
    return round(value * mult) if rounded else math.trunc(value * mult)


def back(*values: int, mult: int = MULT) -> list[float]:
    """What a decoder must give for words that carry `values`: each divided by its multiplier."""
    return [v / mult for v in values]


def close(got: Any, want: list[float] | float) -> bool:
    return got == pytest.approx(want, abs=1e-9)


# --- 50003: 2.10.0 and 2.11.0 (pull request 482's MULT_TIME, not yet 491's word order) ---


def motion_primitive(first: list[float], second: list[float], third: list[float], duration: float,
                     last: float | int, motion_type: int, spline: bool = False) -> bytes:  # fmt: skip
    """TrajectoryPointInterface::writeMotionPrimitive at 2.10.0: three blocks of six times
    MULT_JOINTSTATE, the duration times MULT_TIME (1000000), then the blend radius times MULT_TIME
    (a spline: its type), then the motion type."""
    blocks = [sent(x) for x in (*first, *second, *third)]
    tail = int(last) if spline else sent(last)
    return words(*blocks, sent(duration), tail, motion_type)


def points_2_10() -> list[bytes]:
    movec_third = [0.25, 1.2, 1.0, 0.0, 0.0, 0.0]  # velocity, acceleration, arc mode
    return [
        motion_primitive(list(Q), [1.05] * 6, [1.4] * 6, 2.5, 0.01, 0),  # MOVEJ
        motion_primitive(list(POSE), list(VIA), movec_third, 0.0, 0.02, 3),  # MOVEC
        motion_primitive(list(Q), [0.1] * 6, [-0.2] * 6, 0.008, 2, 51, spline=True),  # quintic spline
    ]


@pytest.mark.parametrize("tag", ["2.10.0", "2.11.0"])
def test_2_10_and_2_11_points_have_the_older_word_order_and_microseconds(tmp_path: Path, tag: str) -> None:
    records = points_2_10()
    assert records[0][72:84] == words(2_500_000, 10_000, 0)  # MULT_TIME 1000000: microseconds
    tables, err = capture(tmp_path, session(tmp_path, tag, 50003, records, (words(0),)))
    assert "trajectory layout motion_type_blocks_us (from the script on 50002)" in err
    assert "urcl_trajectory_points" not in tables  # nothing read in the newest layout
    movej, movec = tables["urcl_trajectory_points_v2"]
    assert (movej["motion_type"], movej["duration"], movej["blend_radius"]) == (0, 2.5, 0.01)
    assert close(movej["target"], list(Q)) and close(movej["velocity_or_via"], [1.05] * 6)
    assert close(movej["acceleration_or_movec"], [1.4] * 6)
    assert (movec["motion_type"], movec["duration"], movec["blend_radius"]) == (3, 0.0, 0.02)
    assert close(movec["velocity_or_via"], list(VIA))
    assert close(movec["acceleration_or_movec"], [0.25, 1.2, 1.0, 0.0, 0.0, 0.0])
    (spline,) = tables["urcl_trajectory_splines"]
    assert (spline["duration"], spline["spline_type"], spline["motion_type"]) == (0.008, 2, 51)
    assert close(spline["velocities"], [0.1] * 6) and close(spline["accelerations"], [-0.2] * 6)
    assert [row["result"] for row in tables["urcl_trajectory_results"]] == [0]


@pytest.mark.parametrize("tag", list(NAMED))
def test_each_release_program_names_one_layout_of_each_message(tag: str) -> None:
    """2.12.0 keeps every line 2.10.0's layout is detected by and adds MOTION_TYPE_MOVEJ_POSE = 6:
    that line, absent, tells them apart. MULT_time is no scale of the reverse and script command
    records: its value (1000 or 1000000) names no layout of theirs."""
    text = program(tag)
    messages = {p.name: m for p in external_spec().protocols for m in p.messages if m.older}
    names = tuple(named_by(messages[proto], text) for proto in ("reverse", "trajectory", "script_command"))
    assert names == tuple([name] for name in NAMED[tag])


# --- 50004: 5-word commands (0.4.0, 1.2.0-1.3.1) and 26-word ones (1.3.2-1.4.0) ---


def command(length: int, code: int, *arguments: float, rounded: bool = True) -> tuple[bytes, list[int]]:
    """ScriptCommandInterface at 0.4.0-1.4.0: the command, its arguments times MULT_JOINTSTATE
    (static_cast's truncation to 1.3.2, round from 1.3.3), zeros to MAX_MESSAGE_LENGTH words.
    Also the argument words, to compare the decoded values with."""
    args = [sent(a, rounded=rounded) for a in arguments]
    return words(code, *args, *[0] * (length - 1 - len(args))), args


@pytest.mark.parametrize("tag", ["0.4.0", "1.2.0", "1.3.1"])
def test_five_word_script_commands(tmp_path: Path, tag: str) -> None:
    payload, payload_args = command(5, 1, 0.57, 0.01, -0.02, 0.057, rounded=False)  # truncated
    voltage, _ = command(5, 2, 12)  # toUnderlying(ToolVoltage::_12V) * MULT_JOINTSTATE
    zero, _ = command(5, 0)
    tables, err = capture(tmp_path, session(tmp_path, tag, 50004, [payload, zero, voltage]))
    assert "script_command layout words_5 (from the script on 50002)" in err
    rows = tables["urcl_script_commands"]
    assert [(r["command"], r["variant"]) for r in rows] == [
        (1, "set_payload"), (0, "zero_ft_sensor"), (2, "set_tool_voltage"),
    ]  # fmt: skip
    arguments = [json.loads(r["arguments"]) for r in rows]
    mass, *cog = back(*payload_args)
    assert close(arguments[0]["mass"], mass) and close(arguments[0]["cog"], cog)
    assert arguments[1] == {} and arguments[2] == {"voltage": 12.0}


@pytest.mark.parametrize("tag", ["1.3.2", "1.3.4"])
def test_twenty_six_word_script_commands(tmp_path: Path, tag: str) -> None:
    """startForceMode before damping and gain scaling (1.5.0): 25 argument words. The robot
    answers the tool contact's end (UNTIL_TOOL_CONTACT_RESULT_CANCELED) on the same port."""
    rounded = tag != "1.3.2"
    frame, selection, wrench = [0.1, 0.2, 0.3, 0.0, 0.0, 1.5], [0, 0, 1, 0, 0, 0], [0, 0, -10.5, 0, 0, 0]
    force, force_args = command(26, 3, *frame, *selection, *wrench, 2, *[0.1] * 6, rounded=rounded)
    payload, payload_args = command(26, 1, 0.57, 0.0, 0.0, 0.057, rounded=rounded)  # 0.57 * 1e6 < 570000
    voltage, end_force, start_contact, end_contact = (command(26, code, *a)[0] for code, a in
                                                      [(2, [24]), (4, []), (5, []), (6, [])])  # fmt: skip
    records = [payload, voltage, force, end_force, start_contact, end_contact]
    tables, err = capture(tmp_path, session(tmp_path, tag, 50004, records, (words(1),)))
    assert "script_command layout words_26 (from the script on 50002)" in err
    rows = tables["urcl_script_commands"]
    assert [r["variant"] for r in rows] == [
        "set_payload", "set_tool_voltage", "start_force_mode", "end_force_mode", "start_tool_contact",
        "end_tool_contact",
    ]  # fmt: skip
    arguments = [json.loads(r["arguments"]) for r in rows]
    mass, *cog = back(*payload_args)
    assert close(arguments[0]["mass"], mass) and close(arguments[0]["cog"], cog)
    assert arguments[1] == {"voltage": 24.0}
    values = back(*force_args)
    assert set(arguments[2]) == {"task_frame", "selection_vector", "wrench", "force_type", "limits"}
    assert close(arguments[2]["task_frame"], values[0:6]) and close(
        arguments[2]["selection_vector"], values[6:12]
    )
    assert close(arguments[2]["wrench"], values[12:18]) and close(arguments[2]["force_type"], 2.0)
    assert close(arguments[2]["limits"], values[19:25])
    assert [r["result"] for r in tables["urcl_tool_contact_results"]] == [1]


# --- 50001: the keepalive count (to 1.3.3) and the read timeout (from 1.3.4) ---


def reverse_1_3_3(keepalive: int) -> list[bytes]:
    """ReverseInterface at 1.3.3: write (SERVOJ), writeTrajectoryControlMessage (START of 3
    points), writeFreedriveControlMessage (START); the first word always keepalive_count_."""
    return [
        words(keepalive, *[sent(q) for q in Q], 1),
        words(keepalive, 1, 3, 0, 0, 0, 0, 3),
        words(keepalive, 1, 0, 0, 0, 0, 0, 6),
    ]


@pytest.mark.parametrize("tag", ["1.3.1", "1.3.3"])
def test_the_first_reverse_word_is_a_keepalive_count_to_1_3_3(tmp_path: Path, tag: str) -> None:
    records = reverse_1_3_3(2)  # setKeepaliveCount(2): two reads may time out
    if tag == "1.3.1":
        records = records[:2]  # freedrive came with 1.3.2
    tables, err = capture(tmp_path, session(tmp_path, tag, 50001, records))
    assert "reverse layout keepalive (from the script on 50002)" in err
    assert "urcl_reverse" not in tables  # no read time-out in seconds made of the count
    (servoj,) = tables["urcl_reverse_v0"]
    assert (servoj["keepalive_count"], servoj["control_mode"]) == (2, 1)
    assert close(servoj["target"], list(Q))
    (start,) = tables["urcl_reverse_trajectory_v0"]
    assert (start["keepalive_count"], start["trajectory_action"], start["point_count"]) == (2, 1, 3)
    if tag == "1.3.3":
        (freedrive,) = tables["urcl_reverse_freedrive_v0"]
        assert (freedrive["keepalive_count"], freedrive["freedrive_action"]) == (2, 1)


def test_from_1_3_4_the_first_reverse_word_is_a_read_timeout(tmp_path: Path) -> None:
    """The same records from 1.3.4 (and an older release's session beside it, another robot):
    each robot's program decides."""
    records = [words(20, *[sent(q) for q in Q], 1)]  # 20 ms
    tables, err = capture(tmp_path, session(tmp_path, "1.3.4", 50001, records))
    assert "reverse layout read_timeout_ms (from the script on 50002)" in err
    (row,) = tables["urcl_reverse"]
    assert (row["read_timeout"], row["control_mode"]) == (0.02, 1)
    assert "urcl_reverse_v0" not in tables
    (tmp_path / "older").mkdir()
    older, _ = capture(tmp_path / "older", session(tmp_path, "1.3.3", 50001, records))
    assert [r["keepalive_count"] for r in older["urcl_reverse_v0"]] == [20]


# --- the spec's rules for `without` and `any_multipliers`, and the dissector ---


def edited_spec(tmp_path: Path, edit: Callable[[str], str]) -> Path:
    root = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", root)
    path = root / "external_control" / "protocols.yaml"
    path.write_text(edit(path.read_text()))
    return root


def test_a_line_both_required_and_without_is_refused(tmp_path: Path) -> None:
    without = "without: [MOTION_TYPE_MOVEJ_POSE = 6]"
    root = edited_spec(tmp_path, lambda t: t.replace(without, "without: [MULT_time = 1000000]"))
    with pytest.raises(SpecError, match=r"detect\(motion_type_blocks_us\).*both required and `without`"):
        load_external(root)


def test_a_multiplier_both_named_and_of_any_value_is_refused(tmp_path: Path) -> None:
    old = "script_lines: [SCRIPT_COMMAND_DATA_DIMENSION = 5, MULT_jointstate = 1000000]"
    root = edited_spec(tmp_path, lambda t: t.replace(old, old.replace("]", ", MULT_time = 1000]")))
    with pytest.raises(SpecError, match=r"detect\(words_5\).*both in `script_lines` and `any_multipliers`"):
        load_external(root)


TSHARK = shutil.which("tshark")


@pytest.mark.skipif(TSHARK is None, reason="tshark is not installed")
def test_the_dissector_reads_each_release_in_its_layout(tmp_path: Path) -> None:
    """The generated Wireshark dissector applies the same detect lines (`without` and
    `any_multipliers` included) to the program it saw on 50002."""
    cases = [
        ("2.10.0", 50003, points_2_10(), "urcl_trajectory", "motion_type_blocks_us", "duration",
         [2.5, 0.0, 0.008]),
        ("1.3.3", 50001, reverse_1_3_3(2), "urcl_reverse", "keepalive", "keepalive_count", [2, 2, 2]),
        ("1.3.1", 50004, [command(5, 2, 24)[0]], "urcl_script_command", "words_5", "voltage", [24.0]),
        ("1.3.4", 50004, [command(26, 2, 12)[0]], "urcl_script_command", "words_26", "voltage", [12.0]),
    ]  # fmt: skip
    for tag, port, records, proto, layout, field, want in cases:
        path = session(tmp_path, tag, port, records)
        args = [str(TSHARK), "-X", f"lua_script:{dissector_path()}", "-r", str(path), "-Y", f"{proto}.layout"]
        args += [
            "-T",
            "fields",
            "-E",
            "aggregator=;",
            "-e",
            f"{proto}.layout",
            "-e",
            f"{proto}.layout_reason",
        ]
        args += ["-e", f"{proto}.{layout}.{field}"]
        result = subprocess.run(args, capture_output=True, text=True, check=True)
        rows = [line.split("\t") for line in result.stdout.splitlines()]
        assert [r[:2] for r in rows] == [[layout, "from the program on 50002"]] * len(records), (
            tag,
            result.stderr,
        )
        assert [float(r[2]) for r in rows if r[2]] == pytest.approx(want), tag
