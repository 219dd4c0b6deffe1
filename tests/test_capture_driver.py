"""A UR driver session in one capture: URCL's reverse, script sender, trajectory and script
command connections beside RTDE, real-time and the dashboard, every protocol to its own
table. Every byte on the wire is packed here with plain `struct` (and framed by dpkt),
from the layouts UR's client library and guides give, not with the project's encoders.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.capture.decoder import capture_tables, decode_to_directory
from rtde_spec.cli.main import main

from .capture_files import Conversation, write

ROBOT, PC = "192.168.56.101", "192.168.56.1"
MULT = 1_000_000  # URCL's MULT_JOINTSTATE and (trajectory) MULT_TIME
Q = [(0.1 * i, -1.5 + 0.01 * i, 1.2, -0.3, 1.57, 3.1415926) for i in range(40)]
SCRIPT = "".join(f"# line {i} of the external control program\n" for i in range(300)).encode()


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def scaled(values: tuple[float, ...] | list[float], mult: int = MULT) -> list[int]:
    return [round(v * mult) for v in values]


def reverse_servoj(q: tuple[float, ...], timeout_ms: int = 20) -> bytes:
    return words(timeout_ms, *scaled(q), 1)  # read timeout, 6 x q, MODE_SERVOJ


def reverse_conversation(port: int = 50001, count: int = len(Q)) -> Conversation:
    conv = Conversation((ROBOT, 40001), (PC, port))
    conv.handshake()
    for q in Q[:count]:
        conv.send("server", reverse_servoj(q), dt=0.008)
    conv.send("server", words(200, 1, 3, 0, 0, 0, 0, 3))  # FORWARD: TRAJECTORY_START of 3 points
    conv.send("server", words(200, 1, 0, 0, 0, 0, 0, 6))  # FREEDRIVE: START
    return conv


def trajectory_conversation(port: int = 50003) -> Conversation:
    conv = Conversation((ROBOT, 40003), (PC, port))
    conv.handshake()
    target = (0.5, -1.0, 1.0, 0.0, 1.5, 0.25)
    # MOVEJ: target, 6 unused, velocity 1.05, acceleration 1.4, flag 0, 3 unused, 2 s, blend 0.05 m, type 0
    conv.send(
        "server", words(*scaled(target), *[0] * 6, 1_050_000, 1_400_000, 0, 0, 0, 0, 2 * MULT, 50_000, 0)
    )
    via = (0.4, 0.1, 0.3, 3.14, 0.0, 0.0)
    pose = (0.5, 0.1, 0.3, 3.14, 0.0, 0.0)
    # MOVEC: pose target, via point, velocity 0.25 m/s, acceleration 1.2, arc mode 1, 0 s, blend 0, type 3
    conv.send("server", words(*scaled(pose), *scaled(via), 250_000, 1_200_000, MULT, 0, 0, 0, 0, 0, 3))
    qd = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6)
    # SPLINE (51), QUINTIC (2): positions, velocities, accelerations, 0.5 s
    conv.send("server", words(*scaled(target), *scaled(qd), *scaled([-x for x in qd]), 500_000, 2, 51))
    conv.send("client", words(0), dt=2.5)  # TRAJECTORY_RESULT_SUCCESS
    return conv


def script_command_conversation() -> Conversation:
    conv = Conversation((ROBOT, 40004), (PC, 50004))
    conv.handshake()
    conv.send("server", words(1, 1_500_000, 0, 0, 50_000, *[0] * 23))  # set_payload 1.5 kg, cog z 5 cm
    conv.send("server", words(0, *[0] * 27))  # zero_ftsensor
    conv.send("server", words(5, *[0] * 27))  # start_tool_contact
    conv.send("server", words(10, 0, 0, 150_000, 0, 0, 1_570_796, *[0] * 21))  # set_tcp_offset
    conv.send("client", words(1), dt=1.0)  # UNTIL_TOOL_CONTACT_RESULT_CANCELED
    return conv


def script_sender_conversation() -> Conversation:
    conv = Conversation((ROBOT, 40002), (PC, 50002))
    conv.handshake()
    conv.send("client", b"request_program\n")
    third = len(SCRIPT) // 3
    for part in (SCRIPT[:third], SCRIPT[third : 2 * third], SCRIPT[2 * third :]):
        conv.send("server", part, dt=0.0005)
    return conv


def dashboard_conversation() -> Conversation:
    conv = Conversation((PC, 41999), (ROBOT, 29999))
    conv.handshake()
    conv.send("server", b"Connected: Universal Robots Dashboard Server\n")
    for request, reply in [
        (b"power on\n", b"Powering on\n"),
        (b"load /programs/missing.urp\n", b"File not found: /programs/missing.urp\n"),
        (b"play\n", b"Failed to execute: play\n"),
        (b"robotmode\n", b"Robotmode: IDLE\n"),
        (b"dance\n", b"could not understand: 'dance'\n"),
    ]:
        conv.send("client", request, dt=0.1)
        conv.send("server", reply, dt=0.004)
    conv.send("client", b"stop\n", dt=0.1)  # the capture ends before its reply
    return conv


def rtde_conversation(port: int = 30004, count: int = 25) -> Conversation:
    """RTDE v2 by the guide: version, setup of timestamp + actual_q, start, data packages."""
    conv = Conversation((PC, 42004), (ROBOT, port))
    conv.handshake()
    conv.send("client", struct.pack(">HBH", 5, ord("V"), 2))
    conv.send("server", struct.pack(">HBB", 4, ord("V"), 1))
    names = b"timestamp,actual_q"
    conv.send("client", struct.pack(">HBd", 11 + len(names), ord("O"), 125.0) + names)
    types = b"DOUBLE,VECTOR6D"
    conv.send("server", struct.pack(">HBB", 4 + len(types), ord("O"), 1) + types)
    conv.send("client", struct.pack(">HB", 3, ord("S")))
    conv.send("server", struct.pack(">HBB", 4, ord("S"), 1))
    for i in range(count):
        conv.send("server", struct.pack(">HBBd6d", 60, ord("U"), 1, i * 0.008, *Q[i]), dt=0.008)
    return conv


def realtime_message(i: int, size: int = 1116) -> bytes:
    """A 5.4-era real-time message: size, time, then q_actual at byte 252 (the guide's layout)."""
    body = bytearray(size)
    struct.pack_into(">i", body, 0, size)
    struct.pack_into(">d", body, 4, 100.0 + i * 0.008)
    struct.pack_into(">6d", body, 252, *Q[i])
    return bytes(body)


def realtime_conversation(port: int = 30003, count: int = 10) -> Conversation:
    conv = Conversation((PC, 43003), (ROBOT, port))
    conv.handshake()
    for i in range(count):
        conv.send("server", realtime_message(i), dt=0.008)
    return conv


def session(tmp_path: Path) -> Path:
    return write(
        tmp_path / "driver.pcap",
        [
            dashboard_conversation(),
            script_sender_conversation(),
            reverse_conversation(),
            trajectory_conversation(),
            script_command_conversation(),
            rtde_conversation(),
            realtime_conversation(),
        ],
    )


def rows(table: Any) -> list[dict[str, Any]]:
    return table.to_pylist()  # type: ignore[no-any-return]


def test_a_driver_session_goes_to_one_table_per_protocol(tmp_path: Path) -> None:
    tables = capture_tables(session(tmp_path))
    reverse = rows(tables["urcl_reverse"])
    assert len(reverse) == len(Q)
    for row, q in zip(reverse, Q, strict=True):
        assert [row[f"target_{j}"] for j in range(6)] == [round(v * MULT) / MULT for v in q]
        assert row["control_mode"] == 1 and row["read_timeout"] == pytest.approx(0.020)
        assert row["robot"] == ROBOT  # the robot is the client on the driver's ports
    (forward,) = rows(tables["urcl_reverse_trajectory"])
    assert (forward["trajectory_action"], forward["point_count"], forward["read_timeout"]) == (1, 3, 0.2)
    assert rows(tables["urcl_reverse_freedrive"])[0]["freedrive_action"] == 1

    points = rows(tables["urcl_trajectory_points"])
    assert [p["motion_type"] for p in points] == [0, 3]
    assert [points[0][f"target_{j}"] for j in range(6)] == [0.5, -1.0, 1.0, 0.0, 1.5, 0.25]
    assert points[0]["duration"] == 2.0 and points[0]["blend_radius"] == 0.05
    assert points[0]["velocity"] == 1.05 and points[0]["acceleration"] == 1.4
    assert [points[1][f"via_or_q_near_{j}"] for j in range(3)] == [0.4, 0.1, 0.3]
    assert points[1]["mode_or_has_q_near"] == 1.0
    spline = rows(tables["urcl_trajectory_splines"])[0]
    assert spline["spline_type"] == 2 and spline["duration"] == 0.5
    assert [spline[f"velocities_{j}"] for j in range(6)] == [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    assert spline["accelerations_5"] == -0.6
    assert rows(tables["urcl_trajectory_results"])[0]["result"] == 0

    commands = rows(tables["urcl_script_commands"])
    assert [c["command"] for c in commands] == [1, 0, 5, 10]
    assert [c["variant"] for c in commands] == [
        "set_payload",
        "zero_ft_sensor",
        "start_tool_contact",
        "set_tcp_offset",
    ]
    assert json.loads(commands[0]["arguments"]) == {"mass": 1.5, "cog": [0.0, 0.0, 0.05]}
    assert json.loads(commands[3]["arguments"])["offset"] == [0.0, 0.0, 0.15, 0.0, 0.0, 1.570796]
    assert rows(tables["urcl_tool_contact_results"])[0]["result"] == 1

    (script,) = rows(tables["urcl_script"])  # the program once, whole
    assert script["script"] == SCRIPT.decode() and script["script_bytes"] == len(SCRIPT)
    assert script["request"] == "request_program" and script["complete"]
    assert script["latency"] == pytest.approx(0.0005, abs=1e-6)

    dash = rows(tables["dashboard"])
    assert [(d["request"], d["command"], d["outcome"]) for d in dash] == [
        ("", "", "greeting"),
        ("power on", "power on", "ok"),
        ("load /programs/missing.urp", "load", "not_found"),
        ("play", "play", "failed"),
        ("robotmode", "robotmode", "ok"),
        ("dance", "", "unknown"),
        ("stop", "stop", "no_reply"),
    ]
    assert dash[2]["argument"] == "/programs/missing.urp"
    assert dash[1]["reply"] == "Powering on" and dash[1]["latency"] == pytest.approx(0.004, abs=1e-6)

    rtde = rows(tables["rtde_outputs_1"])
    assert [r["actual_q_5"] for r in rtde] == [q[5] for q in Q[:25]]
    realtime = rows(tables["realtime"])
    assert [r["time"] for r in realtime] == [100.0 + i * 0.008 for i in range(10)]
    assert [realtime[3][f"q_actual_{j}"] for j in range(6)] == list(Q[3])


def test_remapped_ports_need_the_port_map(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = write(
        tmp_path / "moved.pcap", [reverse_conversation(port=50101), trajectory_conversation(port=50103)]
    )
    assert "urcl_reverse" not in capture_tables(path)
    code = main(["capture", str(path), "-o", str(tmp_path / "out"), "--format", "jsonl",
                 "--port-map", "50101=reverse,50103=trajectory"])  # fmt: skip
    assert code == 0
    out = capsys.readouterr().out
    assert "urcl_reverse (40 rows)" in out and "urcl_trajectory_points (2 rows)" in out
    assert main(["capture", str(path), "-o", str(tmp_path / "o2"), "--port-map", "50101=reversed"]) == 2
    assert "unknown protocol 'reversed'" in capsys.readouterr().err


def test_rtde_primary_and_realtime_on_unusual_ports_by_content(tmp_path: Path) -> None:
    primary = Conversation((PC, 44001), (ROBOT, 40001))
    primary.handshake()
    # a version message: size, type 20, timestamp, source -1, robot message type 3, name, versions
    name = b"URControl"
    body = struct.pack(">QbB", 7, -1, 3) + bytes([len(name)]) + name + struct.pack(">BBii", 5, 15, 0, 1234)
    body += b"01-01-2024, 12:00:00"
    primary.send("server", struct.pack(">iB", 5 + len(body), 20) + body)
    tables = capture_tables(
        write(
            tmp_path / "odd.pcap", [rtde_conversation(port=40004), realtime_conversation(port=40003), primary]
        )
    )
    assert len(rows(tables["rtde_outputs_1"])) == 25
    assert len(rows(tables["realtime"])) == 10
    (version,) = rows(tables["primary_version_message"])
    assert version["project_name"] == "URControl" and version["major_version"] == 5


def test_a_gap_in_the_reverse_stream_loses_only_the_records_it_cuts(tmp_path: Path) -> None:
    conv = Conversation((ROBOT, 40001), (PC, 50001))
    conv.handshake()
    stream = b"".join(reverse_servoj(q) for q in Q)
    pieces = [stream[i : i + 48] for i in range(0, len(stream), 48)]  # 1.5 records per segment
    for n, piece in enumerate(pieces):
        conv.send("server", piece, keep=n != 5)  # bytes 240..287 (records 7 and 8) never captured
    path = write(tmp_path / "gap.pcap", [conv])
    out = tmp_path / "out"
    summary = decode_to_directory(path, out, "jsonl")
    got = [
        json.loads(line)
        for f in (out / "urcl_reverse").rglob("*.jsonl")
        for line in f.read_text().splitlines()
    ]
    kept = [i for i in range(len(Q)) if i not in (7, 8)]
    assert [r["target"] for r in got] == [[round(v * MULT) / MULT for v in Q[i]] for i in kept]
    (conn,) = summary.connections
    assert (conn.gaps, conn.lost_bytes, conn.cut_packages, conn.skipped_bytes) == (1, 48, 1, 16)
    assert any("TCP gaps" in line for line in summary.damage())
    assert main(["capture", str(path), "-o", str(tmp_path / "cli")]) == 3


def test_a_reverse_stream_captured_from_its_middle_finds_the_record_boundary(tmp_path: Path) -> None:
    conv = Conversation((ROBOT, 40001), (PC, 50001))  # no handshake: the capture starts mid-stream
    stream = b"".join(reverse_servoj(q) for q in Q)[12:]  # inside record 0
    for i in range(0, len(stream), 100):
        conv.send("server", stream[i : i + 100])
    path = write(tmp_path / "mid.pcap", [conv])
    summary = decode_to_directory(path, tmp_path / "out", "jsonl")
    (conn,) = summary.connections
    assert conn.lead_in_bytes == 20 and conn.packages == len(Q) - 1
    assert not summary.damage()


def test_a_reverse_record_cut_by_the_end_is_reported(tmp_path: Path) -> None:
    conv = reverse_conversation(count=3)
    conv.send("server", reverse_servoj(Q[0])[:10])
    summary = decode_to_directory(write(tmp_path / "end.pcap", [conv]), tmp_path / "out", "jsonl")
    assert any("ends inside" in line for line in summary.damage())
    assert summary.tables["urcl_reverse"] == 3
