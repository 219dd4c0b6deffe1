"""The session `driver.pcap` was recorded from runs as it did: a driver-like client (URCL's
headless mode) against `rtde-spec serve` in its own process, every port a free one here (the
recording uses the controller's and the driver's own), the program answering on each."""

from __future__ import annotations

import pytest

from rtde_spec.examples.make_driver_capture import DASHBOARD, Ports, run_session

pytestmark = pytest.mark.slow  # the emulator's start-up and a 1 s trajectory: ~10 s on a loaded machine


def test_the_driver_session_runs_the_program_to_its_end_on_free_ports() -> None:
    session = run_session(ports=Ports(**{name: 0 for name in Ports.__dataclass_fields__}))
    assert [command for command, _ in session.dashboard] == DASHBOARD
    assert dict(session.dashboard)["robotmode"] == "Robotmode: RUNNING"
    assert session.trajectory_result == 0  # TRAJECTORY_RESULT_SUCCESS, sent by the program
    assert session.program_closed and session.rtde_rows > 0
    said = session.robot_messages()
    assert "text  [ROBOTINTERFACE] trajectory done" in said
    assert said[-1] == "key  C0A0 PROGRAM_XXX_STOPPED: external_control"
    assert not [line for line in said if "timed out" in line or "runtime" in line.lower()]
