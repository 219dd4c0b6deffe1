"""The generated dissectors of a driver session's other ports (URCL external control, dashboard,
real-time), run by tshark on a struct-built capture, agree with our decoder value by value."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.capture.decoder import capture_tables

from .test_capture_driver import SCRIPT, session
from .test_wireshark import tshark


@pytest.fixture(scope="module")
def capture(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, list[dict[str, Any]]]]:
    path = session(tmp_path_factory.mktemp("driver"))
    return path, {name: table.to_pylist() for name, table in capture_tables(path).items()}


def floats(cell: str) -> list[float]:
    return [float(x) for x in cell.split(",")]


def vector(row: dict[str, Any], name: str, n: int) -> list[float]:
    return [row[f"{name}_{j}"] for j in range(n)]


def test_reverse_interface_every_value(capture: tuple[Path, dict[str, Any]]) -> None:
    path, ours = capture
    got = tshark(
        path, 'urcl_reverse.variant == "motion_target"',
        "urcl_reverse.read_timeout", "urcl_reverse.target", "urcl_reverse.control_mode",
    )  # fmt: skip
    assert len(got) == len(ours["urcl_reverse"]) == 40
    for (timeout, target, mode), mine in zip(got, ours["urcl_reverse"], strict=True):
        assert float(timeout) == pytest.approx(mine["read_timeout"])
        assert floats(target) == pytest.approx(vector(mine, "target", 6), abs=1e-12)
        assert int(mode) == mine["control_mode"]
    (forward,) = tshark(
        path, 'urcl_reverse.variant == "trajectory_control"', "urcl_reverse.trajectory_action",
        "urcl_reverse.point_count",
    )  # fmt: skip
    mine = ours["urcl_reverse_trajectory"][0]
    assert (int(forward[0]), int(forward[1])) == (mine["trajectory_action"], mine["point_count"])
    (freedrive,) = tshark(
        path, 'urcl_reverse.variant == "freedrive_control"', "urcl_reverse.freedrive_action"
    )
    assert int(freedrive[0]) == ours["urcl_reverse_freedrive"][0]["freedrive_action"]


def test_trajectory_points_splines_and_result_every_value(capture: tuple[Path, dict[str, Any]]) -> None:
    path, ours = capture
    scalar = ["velocity", "acceleration", "mode_or_has_q_near", "duration", "blend_radius"]
    got = tshark(
        path, 'urcl_trajectory.variant == "motion_primitive"', "urcl_trajectory.target",
        "urcl_trajectory.via_or_q_near", *(f"urcl_trajectory.{n}" for n in scalar),
        "urcl_trajectory.motion_type",
    )  # fmt: skip
    assert len(got) == len(ours["urcl_trajectory_points"]) == 2
    for row, mine in zip(got, ours["urcl_trajectory_points"], strict=True):
        assert floats(row[0]) == pytest.approx(vector(mine, "target", 6), abs=1e-12)
        assert floats(row[1]) == pytest.approx(vector(mine, "via_or_q_near", 6), abs=1e-12)
        assert [float(x) for x in row[2:7]] == pytest.approx([mine[n] for n in scalar], abs=1e-12)
        assert int(row[7]) == mine["motion_type"]
    (spline,) = tshark(
        path, 'urcl_trajectory.variant == "spline_point"', "urcl_trajectory.positions",
        "urcl_trajectory.velocities", "urcl_trajectory.accelerations", "urcl_trajectory.duration",
        "urcl_trajectory.spline_type",
    )  # fmt: skip
    mine = ours["urcl_trajectory_splines"][0]
    for cell, name in zip(spline[:3], ("positions", "velocities", "accelerations"), strict=True):
        assert floats(cell) == pytest.approx(vector(mine, name, 6), abs=1e-12)
    assert (float(spline[3]), int(spline[4])) == (mine["duration"], mine["spline_type"])
    (result,) = tshark(path, 'urcl_trajectory.variant == "result"', "urcl_trajectory.result")
    assert int(result[0]) == ours["urcl_trajectory_results"][0]["result"]


def test_script_commands_every_argument(capture: tuple[Path, dict[str, Any]]) -> None:
    path, ours = capture
    names = ["mass", "cog", "offset"]
    got = tshark(
        path, "urcl_script_command.command", "urcl_script_command.variant", "urcl_script_command.command",
        *(f"urcl_script_command.{n}" for n in names),
    )  # fmt: skip
    assert len(got) == len(ours["urcl_script_commands"]) == 4
    for row, mine in zip(got, ours["urcl_script_commands"], strict=True):
        assert (row[0], int(row[1])) == (mine["variant"], mine["command"])
        arguments = json.loads(mine["arguments"])
        for cell, name in zip(row[2:], names, strict=True):
            if name in arguments:
                want = arguments[name]
                assert floats(cell) == pytest.approx(want if isinstance(want, list) else [want], abs=1e-12)
            else:
                assert cell == ""
    (result,) = tshark(path, 'urcl_script_command.variant == "result"', "urcl_script_command.result")
    assert int(result[0]) == ours["urcl_tool_contact_results"][0]["result"]


def test_script_sender_request_and_text(capture: tuple[Path, dict[str, Any]]) -> None:
    path, ours = capture
    got = tshark(path, "urcl_script_sender", "urcl_script_sender.request", "urcl_script_sender.script")
    (script,) = ours["urcl_script"]
    assert [r[0] for r in got if r[0]] == [script["request"]]
    assert "".join(r[1] for r in got).replace("\\n", "\n") == script["script"] == SCRIPT.decode()


def test_dashboard_requests_replies_and_outcomes(capture: tuple[Path, dict[str, Any]]) -> None:
    path, ours = capture
    got = tshark(path, "urdashboard", "urdashboard.request", "urdashboard.reply", "urdashboard.command",
                 "urdashboard.outcome", "urdashboard.argument")  # fmt: skip
    requests = [(r[0], r[2], r[4]) for r in got if r[0]]
    replies = [(r[1], r[3]) for r in got if r[1]]
    mine = ours["dashboard"]
    assert requests == [(m["request"], m["command"], m["argument"]) for m in mine if m["request"]]
    assert replies == [(m["reply"], m["outcome"]) for m in mine if m["reply"]]


def test_realtime_every_value(capture: tuple[Path, dict[str, Any]]) -> None:
    path, ours = capture
    got = tshark(path, "urrealtime", "urrealtime.message_size", "urrealtime.time", "urrealtime.q_actual",
                 "urrealtime.q_target")  # fmt: skip
    assert len(got) == len(ours["realtime"]) == 10
    for (size, time, q, q_target), mine in zip(got, ours["realtime"], strict=True):
        assert int(size) == 1116 and float(time) == mine["time"]
        # tshark prints doubles to 15 significant digits
        assert floats(q) == pytest.approx(vector(mine, "q_actual", 6), rel=1e-14)
        assert floats(q_target) == pytest.approx(vector(mine, "q_target", 6), rel=1e-14)
