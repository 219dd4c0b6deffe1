"""`rtde-spec watch` and the message one-liners it prints, on the emulator over loopback."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient, decode_message, encode_message
from rtde_spec.cli.main import main
from rtde_spec.emulator.controller.scenario import Scenario
from rtde_spec.primary import models as pm
from rtde_spec.primary.events import StateChanges, describe_message
from rtde_spec.wire.primary_base import RobotStateMessage

from .helpers import DATA

GOLDEN = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
SCENARIO = Scenario.model_validate({"controller": "5.11.2", "outputs": {"actual_q": [0.5, 0, 0, 0, 0, -0.5]}})


@pytest.fixture
def emu() -> Iterator[EmulatorThread]:
    running = EmulatorThread(
        EmulatorConfig(
            rtde_port=0,
            primary_port=0,
            secondary_port=0,
            scenario=SCENARIO,
            realtime_port=None,
            dashboard_port=None,
        )
    ).start()
    yield running
    running.stop()


def watch(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, list[str], str]:
    code = main(["watch", "--host", "127.0.0.1", *args])
    out, err = capsys.readouterr()
    return code, out.splitlines(), err


def test_version_then_modes_once_then_only_changes(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str]
) -> None:
    code, lines, err = watch(capsys, "--port", str(emu.ports["secondary"]), "--duration", "1")
    assert code == 0 and f"watching 127.0.0.1:{emu.ports['secondary']}" in err
    kinds = [line.split()[1] for line in lines]
    assert kinds == ["version", "state"]  # ten Robot States, the modes did not change after the first
    assert "URControl 5.11.2" in lines[0]
    assert "robot mode 7 (RUNNING)" in lines[1] and "speed slider 1.0" in lines[1]
    assert "safety mode 1 (NORMAL)" in lines[1]


def test_a_speed_slider_set_over_rtde_shows_as_a_change(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str]
) -> None:
    def slide() -> None:
        time.sleep(0.6)
        with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
            recipe = client.setup_inputs(["speed_slider_mask", "speed_slider_fraction"])
            client.send(recipe, speed_slider_mask=1, speed_slider_fraction=0.25)
            time.sleep(0.5)

    setter = threading.Thread(target=slide)
    setter.start()
    code, lines, _ = watch(capsys, "--port", str(emu.ports["primary"]), "--duration", "2")
    setter.join()
    states = [line for line in lines if line.split()[1] == "state"]
    assert code == 0 and len(states) == 2
    assert states[1].split(None, 2)[2] == "speed slider 0.25"  # only what changed


def test_every_robot_state_with_joints_and_pose(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str]
) -> None:
    code, lines, _ = watch(capsys, "--port", str(emu.ports["secondary"]), "--count", "5", "--every")
    poses = [line for line in lines if line.split()[1] == "pose"]
    assert code == 0 and len(lines) == 5 and len(poses) == 3  # version, modes, and a pose per state
    assert "q [rad] 0.5000 0.0000 0.0000 0.0000 0.0000 -0.5000" in poses[0]


@pytest.mark.parametrize("count", [1, 2])
def test_count_is_the_lines_printed(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], count: int
) -> None:
    code, lines, _ = watch(capsys, "--port", str(emu.ports["secondary"]), "--count", str(count))
    assert code == 0 and [line.split()[1] for line in lines] == ["version", "state"][:count]


def test_a_script_is_watched_to_the_programs_end(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    script = tmp_path / "move.script"
    script.write_text('def move():\n  sleep(0.5)\n  textmsg("done")\nend\n')
    started = time.monotonic()
    code, lines, err = watch(capsys, "--port", str(emu.ports["primary"]), "--script", str(script))
    assert code == 0 and "the program ended" in err
    assert time.monotonic() - started >= 0.5
    assert any("[ROBOTINTERFACE] done" in line for line in lines)
    assert "PROGRAM_XXX_STOPPED" in lines[-1]


def test_by_default_the_primary_port_shows_a_script_s_texts_and_the_secondary_says_why_not(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """watch's default port was the secondary 30002, which sends only Robot State and Version (the
    primary/secondary document): a script's texts, its runtime exceptions and its start and stop
    never showed, and a program too short to be seen running kept watch waiting for its end."""
    host = "127.0.0.44"  # the controller's own port numbers, on an address of this test's
    config = EmulatorConfig(host=host, rtde_port=None, realtime_port=None, dashboard_port=None)
    script = tmp_path / "quick.script"
    script.write_text('def quick():\n  textmsg("quick")\nend\n')
    with EmulatorThread(config):
        code = main(["watch", "--host", host, "--script", str(script)])
        out, err = capsys.readouterr()
        assert code == 0 and f"watching {host}:30001" in err and "the program ended" in err
        assert any(line.endswith("[ROBOTINTERFACE] quick") for line in out.splitlines())
        code = main(["watch", "--host", host, "--port", "30002", "--count", "1"])
        out, err = capsys.readouterr()
        assert code == 0 and "note: port 30002 sends only Robot State and the Version message" in err
        assert "come on 30001" in err


def test_json_lines_and_a_script_sent_first(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    script = tmp_path / "hello.script"
    script.write_text('textmsg("watch")\nset_digital_out(2, True)\n')
    code, lines, err = watch(
        capsys, "--port", str(emu.ports["primary"]), "--count", "30", "--json", "--script", str(script)
    )
    assert code == 0 and "sent 2 lines of URScript" in err
    rows = [json.loads(line) for line in lines]
    assert rows[0]["package"] == "version_message" and len(rows) == 30
    assert rows[0]["major_version"] == 5 and rows[0]["minor_version"] == 11
    assert all("received" in r for r in rows)
    # Robot State at 10 Hz, and between them the robot messages the program causes, as a controller
    # sends them: its start and stop (key messages) and its textmsg (a text message)
    states = [r for r in rows if r["package"] == "robot_state"]
    messages = [r for r in rows[1:] if r["package"] != "robot_state"]
    assert len(states) >= 10
    joints = next(s for s in states[0]["sub_packages"] if s["package"] == "joint_data")["joints"]
    assert joints[5]["q_actual"] == -0.5
    assert [r["text_message"] for r in messages if r["package"] == "text_message"] == ["watch"]
    keys = [r["robot_message_title"] for r in messages if r["package"] == "key_message"]
    assert keys == ["PROGRAM_XXX_STARTED", "PROGRAM_XXX_STOPPED"]
    deadline = time.monotonic() + 2
    while not emu.emulator.primary.scripts and time.monotonic() < deadline:
        time.sleep(0.05)
    assert any('textmsg("watch")' in text for _, text in emu.emulator.primary.scripts)


def test_errors_read_only_refused_port_and_missing_script(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    script = tmp_path / "s.script"
    script.write_text("popup('x')\n")
    code, _, err = watch(capsys, "--port", "30012", "--script", str(script))
    assert code == 2 and "read-only" in err
    code, _, err = watch(capsys, "--port", "1", "--count", "1")
    assert code == 1 and "127.0.0.1:1" in err and "cannot connect" in err
    code, _, err = watch(capsys, "--port", "30002", "--script", str(tmp_path / "nope.script"))
    assert code == 2 and "nope.script" in err


def test_a_controller_that_closes_is_an_error_after_what_it_sent(capsys: pytest.CaptureFixture[str]) -> None:
    running = EmulatorThread(
        EmulatorConfig(
            rtde_port=0,
            primary_port=0,
            secondary_port=0,
            scenario=SCENARIO,
            realtime_port=None,
            dashboard_port=None,
        )
    ).start()
    port = running.ports["secondary"]
    stopper = threading.Timer(0.5, running.stop)
    stopper.start()
    code, lines, err = watch(capsys, "--port", str(port))
    stopper.join()
    assert code == 1 and "closed the connection" in err and lines[0].split()[1] == "version"


@pytest.mark.parametrize(
    "case", [c for c in GOLDEN if c["message"].endswith("_message")], ids=lambda c: c["message"]
)
def test_every_robot_message_is_one_escaped_line_with_its_text(case: dict[str, Any]) -> None:
    message = decode_message(bytes.fromhex(case["hex"]))
    line = describe_message(message)
    assert line is not None and "\n" not in line and "\x1b" not in line
    kind = case["message"].removesuffix("_message")
    assert line.startswith(kind + "  ")
    for key in ("text_message", "report_text", "key_text_message", "runtime_exception_text_message"):
        if case["fields"].get(key):
            assert case["fields"][key] in line
    if "robot_message_code" in case["fields"]:
        assert f"C{case['fields']['robot_message_code']}A{case['fields']['robot_message_argument']}" in line


def test_wire_text_cannot_drive_the_terminal() -> None:
    hostile = pm.TextMessage(timestamp=1, source=-2, robot_message_type=0, text_message="a\x1b[2Jb\nc")
    line = describe_message(decode_message(encode_message(hostile)))
    assert line == "text  [ROBOTINTERFACE] a\\x1b[2Jb\\x0ac"


def test_state_changes_report_only_what_changed() -> None:
    def state(mode: int, running: bool, slider: float) -> RobotStateMessage:
        part = pm.RobotModeData(
            timestamp=0, is_real_robot_connected=True, is_real_robot_enabled=True, is_robot_power_on=True,
            is_emergency_stopped=False, is_protective_stopped=False, is_program_running=running,
            is_program_paused=False, robot_mode=mode, control_mode=0, target_speed_fraction=slider,
            speed_scaling=1.0, target_speed_fraction_limit=1.0, reserved=0,
        )  # fmt: skip
        message = decode_message(encode_message(RobotStateMessage(sub_packages=[part])))
        assert isinstance(message, RobotStateMessage)
        return message

    changes = StateChanges()
    first = changes.update(state(5, False, 1.0))
    assert first["robot mode"] == "5 (IDLE)" and first["program running"] == "False" and len(first) == 8
    assert changes.update(state(5, False, 1.0)) == {}
    assert changes.update(state(7, True, 1.0)) == {"robot mode": "7 (RUNNING)", "program running": "True"}
    assert changes.describe(state(7, True, 0.5)) == "speed slider 0.5"
    assert changes.update(decode_message(bytes.fromhex(GOLDEN[19]["hex"]))) == {}  # not a Robot State
