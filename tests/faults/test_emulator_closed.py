"""The emulator stays closed (issue 31.4): the programs folder, hostile names, inputs out of range.

Real sockets on 127.0.0.1: a dashboard client as netcat would be, an RTDE client sending
inputs. A `.urp` whose `.script` is a symlink out of `--programs` is not loaded; a NUL byte,
a 300-character name or a loop of links is the controller's "File not found" reply, and
the connection stays up; a NaN, infinite or out-of-range speed slider never reaches the
arm, which keeps moving to its targets.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.rtde.client import RtdeClient
from tests.test_dashboard import Dashboard

SECRET = "the first line of a file outside the programs folder"


@pytest.fixture
def emu(tmp_path: Path) -> Iterator[EmulatorThread]:
    programs = tmp_path / "programs"
    programs.mkdir()
    outside = tmp_path / "secret.script"
    outside.write_text(f"{SECRET}\n")
    (programs / "leak.urp").write_bytes(b"\x1f\x8b PolyScope's file")
    os.symlink(outside, programs / "leak.script")  # the .script beside the .urp leads out
    os.symlink(programs / "loop_a.script", programs / "loop_b.script")
    os.symlink(programs / "loop_b.script", programs / "loop_a.script")
    (programs / "inside.script").write_text('def inside():\n  textmsg("in")\nend\n')
    os.symlink(programs / "inside.script", programs / "alias.script")  # a link that stays inside
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=0, dashboard_port=0, programs=programs, realtime_port=None
    )
    emulator = EmulatorThread(config).start()
    yield emulator
    emulator.stop()


def test_a_urp_whose_script_links_outside_is_not_found(emu: EmulatorThread) -> None:
    dash = Dashboard(emu.ports["dashboard"])
    try:
        assert dash.ask("load leak.urp") == "File not found: leak.urp"
        assert dash.ask("load leak.script") == "File not found: leak.script"
        assert dash.ask("play") == "Failed to execute: play"  # nothing was loaded
        assert dash.ask("load alias.script") == "Loading program: alias.script"  # links inside are fine
    finally:
        dash.close()


@pytest.mark.parametrize(
    "name",
    ["a\0b.script", "x" * 300 + ".script", "loop_a.script", "../" * 50 + "etc/passwd", "programs/\0"],
)
def test_hostile_names_get_the_controllers_reply_and_the_connection_stays(
    emu: EmulatorThread, name: str
) -> None:
    dash = Dashboard(emu.ports["dashboard"])
    try:
        reply = dash.ask(f"load {name}")
        assert reply.startswith("File not found: "), reply
        assert dash.ask("robotmode") == "Robotmode: RUNNING"  # still answering on the same connection
    finally:
        dash.close()


def _send_slider(client: RtdeClient, value: float) -> None:
    client.send(client.inputs, {"speed_slider_mask": 1, "speed_slider_fraction": value})  # type: ignore[attr-defined]


def _slider_and_q(client: RtdeClient) -> tuple[float, list[float]]:
    deadline = time.monotonic() + 0.5
    record = client.receive()
    while time.monotonic() < deadline:  # the newest package, after the input was applied
        record = client.receive()
    return float(record.target_speed_fraction), [float(v) for v in record.actual_q]


@pytest.mark.slow  # seconds of a moving arm: CI runs it
def test_slider_values_out_of_range_never_poison_the_arm(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        client.setup_outputs(["target_speed_fraction", "actual_q"], 125)
        client.inputs = client.setup_inputs(["speed_slider_mask", "speed_slider_fraction"])  # type: ignore[attr-defined]
        client.start()
        _send_slider(client, 0.5)
        assert _slider_and_q(client)[0] == 0.5
        for bad in (math.nan, math.inf, -math.inf):
            _send_slider(client, bad)
            slider, q = _slider_and_q(client)
            assert slider == 0.5, f"{bad} reached the slider"
            assert all(math.isfinite(v) for v in q), q
        _send_slider(client, -1.0)
        assert _slider_and_q(client)[0] == 0.0  # clamped, as the controller's slider is
        _send_slider(client, 7.0)
        assert _slider_and_q(client)[0] == 1.0
        model = emu.emulator.model
        program = "def go():\n  movej([0.2, -1.4, 1.4, -1.5, -1.5, 0.1], a=3, v=2)\nend\n"
        started = emu.call(lambda: (model.load_program(program), model.play())[1])  # on the control loop
        assert started, "the program was refused: the arm cannot move"
        deadline = time.monotonic() + 10
        q: list[float] = []
        while time.monotonic() < deadline:
            _, q = _slider_and_q(client)
            if abs(q[0] - 0.2) < 1e-4:
                break
        assert abs(q[0] - 0.2) < 1e-4 and all(math.isfinite(v) for v in q), q
