"""More of ur_rtde's RTDEControlInterface (pip ur_rtde) against the emulator: the calls users make
beyond the plain moves (tests/test_ur_rtde_control.py), each held to what a robot answers.

The client is unchanged: it uploads its own control script to the real-time port, and uploads it
again (with the path injected) for every path move. The emulator runs in its own process on a
loopback address of its own, its log read as it goes, so a test can wait for what it reports.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.metamodel.arms import arm_model

from .ur_rtde_robot import Robot, settle_until, ur_rtde_robot

rtde_control = pytest.importorskip("rtde_control", reason="ur_rtde is installed by the test extra")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")

HOST = "127.0.0.73"
RAD, METRE = 1e-4, 1e-4
UR5E = arm_model("UR5e")
pytestmark = [
    pytest.mark.slow,
    pytest.mark.xdist_group("ur-rtde-control-more"),
    pytest.mark.fixed_ports(HOST),
]


@pytest.fixture(scope="module")
def robot() -> Iterator[Robot]:
    with ur_rtde_robot(HOST, rtde_control, rtde_receive) as robot:
        yield robot


def test_get_forward_kinematics_takes_the_tcp_offset_it_is_given(robot: Robot) -> None:
    q = list(robot.receive.getActualQ())
    q[0] += 0.3
    tcp = [0.01, 0.02, 0.15, 0.0, 0.1, 0.0]
    assert robot.control.getForwardKinematics(q, tcp) == pytest.approx(kin.forward(UR5E, q, tcp), abs=1e-6)
    here = robot.receive.getActualQ()
    assert robot.control.getForwardKinematics() == pytest.approx(kin.forward(UR5E, here), abs=1e-6)


def test_get_target_waypoint_is_the_goal_of_the_move_under_way(robot: Robot) -> None:
    start = robot.receive.getActualTCPPose()
    goal = [start[0], start[1], start[2] + 0.1, *start[3:]]
    assert robot.control.moveL(goal, 0.1, 0.5, True)  # asynchronous: under way for about 1 s
    time.sleep(0.3)
    assert robot.control.getTargetWaypoint() == pytest.approx(goal, abs=1e-6)
    settle_until(lambda: robot.receive.getActualTCPPose() == pytest.approx(goal, abs=METRE))
    settle_until(lambda: robot.control.getAsyncOperationProgress() < 0)
    assert robot.control.getTargetWaypoint() == pytest.approx(goal, abs=1e-6)  # at rest: where it is


def test_freedrive_status_is_normal_operation_away_from_singularities(robot: Robot) -> None:
    # Script Manual: 0 normal operation, 1 near a singularity, 2 too close to one
    assert robot.control.freedriveMode()
    assert robot.control.getFreedriveStatus() == 0
    assert robot.control.endFreedriveMode()
    assert robot.control.getFreedriveStatus() == 0


def test_servoc_to_where_the_arm_is_holds_it_and_the_script_keeps_running(robot: Robot) -> None:
    # a servo stream starts where the arm is: the script's servoc thread calls servoc there again
    # and again, each call a control step as on a robot (the calls took no time: a loop that never
    # waited, and the script faulted)
    here = robot.receive.getActualTCPPose()
    assert robot.control.servoC(here, 0.1, 1.2, 0.0)
    deadline = time.monotonic() + 4.0  # the old loop faulted within 2 s, its statement budget spent
    while time.monotonic() < deadline:
        assert robot.control.isProgramRunning()
        time.sleep(0.1)
    assert robot.receive.getActualTCPPose() == pytest.approx(here, abs=1e-9)
    # ur_rtde sends no clear after servoC, which its script waits for: this call waits 4 s for it
    robot.control.servoStop()
    assert robot.control.reuploadScript()  # a fresh script for the next test
    settle_until(robot.control.isProgramRunning)


def test_path_moves_still_upload_after_the_script_client_stopped_reading(robot: Robot) -> None:
    # ur_rtde's script client never reads the real-time port's 500 Hz stream; a robot keeps its
    # connection (every path move and reupload goes through it), the emulator dropped it
    settle_until(
        lambda: any("stopped reading" in line for line in robot.log),
        60,
        "the script client never fell behind",
    )
    assert not [line for line in robot.log if "dropping realtime client" in line]  # (ur_rtde would hang)
    q = list(robot.receive.getActualQ())
    w1, w2 = [q[0] + 0.2, *q[1:]], [q[0] + 0.2, q[1] - 0.1, *q[2:]]
    assert robot.control.moveJ([[*w1, 0.7, 1.2, 0.02], [*w2, 0.7, 1.2, 0.0]])
    settle_until(lambda: robot.receive.getActualQ() == pytest.approx(w2, abs=RAD))
    assert robot.control.reuploadScript()
    settle_until(robot.control.isProgramRunning)
    assert robot.control.moveJ(q)
    settle_until(lambda: robot.receive.getActualQ() == pytest.approx(q, abs=RAD))
