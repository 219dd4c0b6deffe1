"""The trajectory point layout of a URCL session, chosen from the program the driver sent on
the script sender port (50002), or from the records when the capture holds no program.

Each session is a real pcap file: the robot requests the program, the driver sends a
program text carrying one URCL version's lines (as the sources in
spec/external_control/protocols.yaml give them, the driver's multipliers filled in), the
driver starts a trajectory on the reverse interface and writes its points on 50003 in
that version's layout, one point per segment as URCL writes them, and the robot answers.
`rtde-spec capture` must put the points in that layout's table with their values in SI
units and say on stderr which layout it used and why.
"""

from __future__ import annotations

import json
import re
import shutil
import struct
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.errors import SpecError
from rtde_spec.external.codec import record_codec
from rtde_spec.metamodel.external import external_spec, load_external

from .capture_files import Conversation, run_capture, write
from .helpers import ROOT

ROBOT, PC = "192.168.56.101", "192.168.56.1"
Q = (0.1, -1.5, 1.2, -0.3, 1.57, 3.1415926)
QD = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6)
POSE = (0.5, 0.1, 0.3, 3.14, 0.0, 0.0)

# The lines that tell the versions apart, as the cited external_control.urscript versions have them
V0_LINES = ["TRAJECTORY_POINT_JOINT = 0", "TRAJECTORY_POINT_CARTESIAN = 1", "TRAJECTORY_DATA_DIMENSION = 7"]
V1_LINES = [*V0_LINES[:2], "TRAJECTORY_POINT_JOINT_SPLINE = 2", "TRAJECTORY_DATA_DIMENSION = 3*6 + 1"]
MOTION = ["MOVEJ", "MOVEL", "MOVEP", "MOVEC", "OPTIMOVEJ", "OPTIMOVEL"]
POSE_JOINT = [
    "MOVEJ_POSE",
    "MOVEL_JOINT",
    "MOVEP_JOINT",
    "MOVEC_JOINT",
    "MOVEC_JOINT_POSE",
    "MOVEC_POSE_JOINT",
]
V2_LINES = [f"MOTION_TYPE_{name} = {i}" for i, name in enumerate(MOTION)] + ["MOTION_TYPE_SPLINE = 51"]
NEWEST_LINES = [f"MOTION_TYPE_{name} = {i}" for i, name in enumerate(MOTION + POSE_JOINT)]
NEWEST_LINES += [
    "MOTION_TYPE_OPTIMOVEJ_POSE = 12",
    "MOTION_TYPE_OPTIMOVEL_JOINT = 13",
    "MOTION_TYPE_SPLINE = 51",
]


def program(lines: list[str], mult_time: int) -> bytes:
    """An external control program as the driver sends it: its multipliers filled in."""
    head = ["# HEADER_BEGIN", "", "steptime = get_steptime()", "MULT_jointstate = 1000000",
            f"MULT_time = {mult_time}", "", "#Constants", "MODE_FORWARD = 3", "TRAJECTORY_MODE_RECEIVE = 1",
            "TRAJECTORY_MODE_CANCEL = -1", ""]  # fmt: skip
    body = [f"# line {i} of the program" for i in range(200)]
    return "\n".join([*head, *lines, "", *body, "# NODE_CONTROL_LOOP_ENDS", ""]).encode()


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def script_sender(text: bytes, time: float, port: int = 40002, lose: int | None = None) -> Conversation:
    conv = Conversation((ROBOT, port), (PC, 50002), time=time)
    conv.handshake()
    conv.send("client", b"request_program\n")
    third = len(text) // 3
    for n, part in enumerate((text[:third], text[third : 2 * third], text[2 * third :])):
        conv.send("server", part, dt=0.0005, keep=n != lose)
    return conv


def reverse_start(points: int, time: float) -> Conversation:
    conv = Conversation((ROBOT, 40001), (PC, 50001), time=time)
    conv.handshake()
    conv.send("server", words(200, 0, 0, 0, 0, 0, 0, 3))  # FORWARD, NOOP
    conv.send("server", words(200, 1, points, 0, 0, 0, 0, 3))  # FORWARD, START of `points`
    return conv


def trajectory(records: list[bytes], time: float, handshake: bool = True) -> Conversation:
    conv = Conversation((ROBOT, 40003), (PC, 50003), time=time)
    if handshake:
        conv.handshake()
    for record in records:
        conv.send("server", record, dt=0.001)  # one write, one segment, as URCL writes a point
    conv.send("client", words(0), dt=1.5)  # TRAJECTORY_RESULT_SUCCESS
    return conv


def session(tmp_path: Path, text: bytes | None, records: list[bytes]) -> Path:
    convs = [script_sender(text, 1_700_000_000.0)] if text is not None else []
    convs += [trajectory(records, 1_700_000_001.0), reverse_start(len(records), 1_700_000_001.5)]
    return write(tmp_path / "session.pcap", convs)


def capture(tmp_path: Path, path: Path, *args: str) -> tuple[dict[str, list[dict[str, Any]]], str]:
    """The tables `rtde-spec capture` wrote (JSON Lines rows by table, in capture order) and its stderr."""
    out = tmp_path / "out"
    done = run_capture(str(path), "-o", str(out), "--format", "jsonl", *args, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    tables: dict[str, list[dict[str, Any]]] = {}
    for table in sorted(p for p in out.iterdir() if p.is_dir()):
        rows = [
            {**json.loads(line), "robot": robot.name.removeprefix("robot=")}
            for robot in table.glob("robot=*")
            for f in robot.rglob("*.jsonl")
            for line in f.read_text().splitlines()
        ]
        tables[table.name] = sorted(rows, key=lambda r: r["capture_time"])
    for note in re.findall(r"trajectory layout [^;\n]*", done.stderr):  # the connection's line says it too
        assert note in done.stdout, (note, done.stdout)
    return tables, done.stderr


def trajectory_tables(tables: dict[str, list[dict[str, Any]]]) -> set[str]:
    return {t for t in tables if t.startswith("urcl_trajectory_") and t != "urcl_trajectory_results"}


def close(got: list[float], want: tuple[float, ...] | list[float]) -> bool:
    return got == pytest.approx(list(want), abs=1e-6)


def packed(layout: str | None, variant: str, values: dict[str, Any]) -> bytes:
    """One trajectory point of the named layout (None: the newest), packed by the spec's codec."""
    return record_codec("trajectory", "trajectory_point", layout).encode(variant, values)


def v0_points() -> list[bytes]:
    return [
        packed(
            "cartesian_flag_9", "point", {"positions": p, "duration": t, "blend_radius": r, "cartesian": c}
        )
        for p, t, r, c in [(Q, 2.0, 0.05, 0), (POSE, 1.25, 0.0, 1), (Q, 0.5, 0.0, 0)]
    ]


def v1_points() -> list[bytes]:
    spline = {"positions": Q, "velocities": QD, "accelerations": [-x for x in QD], "blend_radius": 0.0}
    return [
        packed("point_type_21", "point", {**spline, "duration": 0.5, "point_type": 2}),  # JOINT_SPLINE
        packed("point_type_21", "point", {**spline, "duration": 2.0, "point_type": 0}),  # JOINT_POINT
    ]


def newest_spline(duration: float = 0.25) -> bytes:
    values = {"positions": Q, "velocities": QD, "accelerations": QD, "duration": duration, "spline_type": 1}
    return packed(None, "spline_point", {**values, "motion_type": 51})


def test_the_oldest_layout_from_the_program_goes_to_its_own_table(tmp_path: Path) -> None:
    records = v0_points()
    assert words(2000, 50, 0) == records[0][24:36]  # MULT_TIME 1000: milliseconds, millimetres
    tables, err = capture(tmp_path, session(tmp_path, program(V0_LINES, 1000), records))
    assert trajectory_tables(tables) == {"urcl_trajectory_points_v0"}
    points = tables["urcl_trajectory_points_v0"]
    assert [p["duration"] for p in points] == [2.0, 1.25, 0.5]
    assert [p["cartesian"] for p in points] == [0, 1, 0]
    assert close(points[0]["positions"], Q) and close(points[1]["positions"], POSE)
    assert points[0]["blend_radius"] == 0.05
    assert "trajectory layout cartesian_flag_9 (from the script on 50002)" in err
    assert [r["result"] for r in tables["urcl_trajectory_results"]] == [0]


def test_the_point_type_layout_from_the_program(tmp_path: Path) -> None:
    records = v1_points()
    assert words(500, 0, 2) == records[0][72:84]  # 0.5 s as 500, JOINT_SPLINE
    tables, err = capture(tmp_path, session(tmp_path, program(V1_LINES, 1000), records))
    assert trajectory_tables(tables) == {"urcl_trajectory_points_v1"}
    spline, joint = tables["urcl_trajectory_points_v1"]
    assert (spline["point_type"], spline["duration"], joint["point_type"], joint["duration"]) == (
        2,
        0.5,
        0,
        2.0,
    )
    assert close(spline["positions"], Q) and close(spline["velocities"], QD)
    assert close(spline["accelerations"], [-x for x in QD])
    assert "trajectory layout point_type_21 (from the script on 50002)" in err


def test_motion_types_with_millisecond_durations_from_the_program(tmp_path: Path) -> None:
    """URCL with motion types before MULT_TIME became 1e6: the program says `MULT_time = 1000`."""
    movej = {"target": Q, "velocity_or_via": [1.05] * 6, "acceleration_or_movec": [1.4] * 6,
             "duration": 2.0, "blend_radius": 0.05, "motion_type": 0}  # fmt: skip
    spline = {"positions": Q, "velocities": QD, "accelerations": QD, "duration": 0.25, "spline_type": 2,
              "motion_type": 51}  # fmt: skip
    records = [
        packed("motion_type_ms", "motion_primitive", movej),
        packed("motion_type_ms", "spline_point", spline),
    ]
    assert words(250, 2, 51) == records[1][72:84]
    tables, err = capture(tmp_path, session(tmp_path, program(V2_LINES, 1000), records))
    assert trajectory_tables(tables) == {"urcl_trajectory_points_v2", "urcl_trajectory_splines"}
    (point,) = tables["urcl_trajectory_points_v2"]
    assert (point["duration"], point["blend_radius"], point["motion_type"]) == (2.0, 0.05, 0)
    assert close(point["velocity_or_via"], [1.05] * 6) and close(point["acceleration_or_movec"], [1.4] * 6)
    (row,) = tables["urcl_trajectory_splines"]
    assert (row["duration"], row["spline_type"]) == (0.25, 2) and close(row["velocities"], QD)
    assert "trajectory layout motion_type_ms (from the script on 50002)" in err


def test_the_newest_layout_from_the_program(tmp_path: Path) -> None:
    movej = {"target": Q, "via_or_q_near": [0.0] * 6, "velocity": 1.05, "acceleration": 1.4,
             "mode_or_has_q_near": 0.0, "unused": [0, 0, 0], "duration": 2.0, "blend_radius": 0.05,
             "motion_type": 0}  # fmt: skip
    records = [packed(None, "motion_primitive", movej), newest_spline()]
    assert words(2_000_000, 50_000, 0) == records[0][72:84]  # MULT_TIME 1000000
    tables, err = capture(tmp_path, session(tmp_path, program(NEWEST_LINES, 1_000_000), records))
    assert trajectory_tables(tables) == {"urcl_trajectory_points", "urcl_trajectory_splines"}
    (point,) = tables["urcl_trajectory_points"]
    assert (point["duration"], point["velocity"], point["acceleration"]) == (2.0, 1.05, 1.4)
    assert tables["urcl_trajectory_splines"][0]["duration"] == 0.25
    assert "trajectory layout motion_type_us (from the script on 50002)" in err


def test_without_the_program_36_byte_segments_leave_one_layout(tmp_path: Path) -> None:
    tables, err = capture(tmp_path, session(tmp_path, None, v0_points()))
    assert trajectory_tables(tables) == {"urcl_trajectory_points_v0"}
    assert [p["duration"] for p in tables["urcl_trajectory_points_v0"]] == [2.0, 1.25, 0.5]
    assert (
        "trajectory layout cartesian_flag_9 (from the records: no other layout fits them; no script seen)"
        in err
    )


def test_without_the_program_84_byte_points_are_read_as_the_newest_and_it_says_so(tmp_path: Path) -> None:
    tables, err = capture(tmp_path, session(tmp_path, None, v1_points()))
    # point types 2 and 0 are MOVEP and MOVEJ to the newest layout: no record rules it out
    assert trajectory_tables(tables) == {"urcl_trajectory_points"}
    assert (
        "trajectory layout motion_type_us (assumed: newest of the layouts the records fit, "
        "motion_type_us, motion_type_blocks_us, motion_type_ms, point_type_21; no script seen)"
    ) in err


def test_a_program_that_names_no_layout_leaves_the_choice_to_the_records(tmp_path: Path) -> None:
    records = [newest_spline()] * 2  # 51 is no point type: point_type_21 is ruled out
    custom = program(NEWEST_LINES, 1_000_000).replace(b"MULT_time", b"MULT_velacc = 100000000\nMULT_time")
    tables, err = capture(tmp_path, session(tmp_path, custom, records))
    assert len(tables["urcl_trajectory_splines"]) == 2
    assert (
        "trajectory layout motion_type_us (assumed: newest of the layouts the records fit, motion_type_us, "
        "motion_type_blocks_us, motion_type_ms; the script on 50002 names none)"
    ) in err


def test_a_capture_begun_mid_session_takes_the_robots_later_program(tmp_path: Path) -> None:
    """The trajectory connection was open before the capture began; the program requested later
    (the robot's program restarted), with a segment of it lost until the capture's end, is the
    same driver's: the end of the capture reads it whole before choosing."""
    text = "".join(f"# a comment line {i} before the program's own\n" for i in range(100)).encode()
    text += program(V1_LINES, 1000)
    assert len(text) // 3 < text.index(b"TRAJECTORY_POINT_JOINT_SPLINE")  # after the lost segment
    late = trajectory(v1_points(), 1_700_000_000.0, handshake=False)
    later = script_sender(text, 1_700_000_001.0, port=40012, lose=0)
    tables, err = capture(tmp_path, write(tmp_path / "late.pcap", [late, later]), "--lenient")
    assert trajectory_tables(tables) == {"urcl_trajectory_points_v1"}
    assert "trajectory layout point_type_21 (from a later script on 50002)" in err


def test_each_robot_reads_its_own_program(tmp_path: Path) -> None:
    other = "192.168.56.102"
    old = script_sender(program(V0_LINES, 1000), 1_700_000_000.0)
    new = Conversation((other, 40002), (PC, 50002), time=1_700_000_000.2)
    new.handshake()
    new.send("client", b"request_program\n")
    new.send("server", program(V1_LINES, 1000), dt=0.0005)
    second = Conversation((other, 40003), (PC, 50003), time=1_700_000_001.0)
    second.handshake()
    for record in v1_points():
        second.send("server", record, dt=0.001)
    path = write(tmp_path / "two.pcap", [old, new, trajectory(v0_points(), 1_700_000_001.0), second])
    tables, err = capture(tmp_path, path)
    assert {r["robot"] for r in tables["urcl_trajectory_points_v0"]} == {ROBOT}
    assert {r["robot"] for r in tables["urcl_trajectory_points_v1"]} == {other}
    assert "trajectory layout cartesian_flag_9 (from the script on 50002)" in err
    assert "trajectory layout point_type_21 (from the script on 50002)" in err


def test_the_spec_refuses_detect_lines_that_cannot_tell_layouts_apart(tmp_path: Path) -> None:
    root = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", root)
    path = root / "external_control" / "protocols.yaml"
    text = path.read_text()
    v0 = "script_lines: [TRAJECTORY_DATA_DIMENSION = 7, MULT_time = 1000, MULT_jointstate = 1000000]"
    assert v0 in text
    path.write_text(text.replace(v0, "script_lines: [MULT_time = 1000, MULT_jointstate = 1000000]"))
    with pytest.raises(SpecError, match=r"detect lines of \w+ and \w+ cannot tell them apart"):
        load_external(root)


def test_every_layout_of_the_trajectory_point_has_detect_lines_and_a_table() -> None:
    message = external_spec().protocol("trajectory").messages[0]
    layouts = message.layouts()
    assert [name for _, name, _, _ in layouts] == [
        "motion_type_us", "motion_type_blocks_us", "motion_type_ms", "point_type_21", "cartesian_flag_9",
    ]  # fmt: skip
    assert all(detect is not None and detect.source for _, _, detect, _ in layouts)
    tables = {v.table for o in message.older for v in o.variants}
    assert {"urcl_trajectory_points_v2", "urcl_trajectory_points_v1", "urcl_trajectory_points_v0"} <= tables


def test_headless_mode_reads_the_program_sent_to_the_primary_port(tmp_path: Path) -> None:
    """A driver in headless mode sends its program to the robot's 30002 instead of serving it on
    50002: that text names the layout just as well."""
    text = program(V1_LINES, 1000)
    sent = Conversation((PC, 45002), (ROBOT, 30002), time=1_700_000_000.0)
    sent.handshake()
    half = len(text) // 2
    sent.send("client", text[:half], dt=0.0005)
    sent.send("client", text[half:], dt=0.0005)
    records = v1_points()
    convs = [sent, trajectory(records, 1_700_000_001.0), reverse_start(len(records), 1_700_000_001.5)]
    tables, err = capture(tmp_path, write(tmp_path / "headless.pcap", convs))
    assert trajectory_tables(tables) == {"urcl_trajectory_points_v1"}
    assert [p["duration"] for p in tables["urcl_trajectory_points_v1"]] == [0.5, 2.0]
    assert "trajectory layout point_type_21 (from the script on 30002)" in err
    assert [r["script"] for r in tables["primary_scripts"]] == [text.decode()]  # one row: one send
