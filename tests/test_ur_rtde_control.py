"""ur_rtde's RTDEControlInterface (pip ur_rtde) drives the emulated arm with its own control script.

The client uploads its 1,175-line `def rtde_control():` program to the real-time port and talks
to it through the RTDE input and output registers, as against a robot. Each command is held to
what it says, seen through ur_rtde's RTDEReceiveInterface: motions end at their targets
(1e-4 rad / 1e-4 m). The emulator runs in its own process (ur_rtde holds the GIL while it waits
for a reply) on a loopback address of its own, since ur_rtde's ports are fixed.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.metamodel.arms import arm_model

from .ur_rtde_robot import Robot, control_mode, serve, settle_until, ur_rtde_robot

rtde_control = pytest.importorskip("rtde_control", reason="ur_rtde is installed by the test extra")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")
rtde_io = pytest.importorskip("rtde_io", reason="ur_rtde is installed by the test extra")

HOST = "127.0.0.71"
RAD, METRE = 1e-4, 1e-4
POSITION, TEACH, FORCE = 0, 1, 2  # the Robot Mode Data's control mode (primary port)
# ur_rtde needs the controller's own ports on its host: every test of this module in one xdist
# worker (one emulator for them all), taking turns for the ports with other runs on the machine
pytestmark = [
    pytest.mark.slow,
    pytest.mark.xdist_group("ur-rtde-control"),
    pytest.mark.fixed_ports(HOST, "127.0.0.72"),
]


@pytest.fixture(scope="module")
def robot() -> Iterator[Robot]:
    with ur_rtde_robot(HOST, rtde_control, rtde_receive) as robot:
        yield robot


def settle(robot: Robot, seconds: float = 0.1) -> None:
    time.sleep(seconds)  # a few RTDE packages, so the receive interface shows the last step


def test_the_control_script_runs_and_movej_ends_at_its_target(robot: Robot) -> None:
    assert robot.control.isConnected() and robot.control.isProgramRunning()
    q = robot.receive.getActualQ()
    target = [q[0] + 0.2, q[1] - 0.1, q[2] + 0.1, q[3], q[4], q[5] + 0.3]
    assert robot.control.moveJ(target, 1.05, 1.4)
    settle(robot)
    assert robot.receive.getActualQ() == pytest.approx(target, abs=RAD)
    assert robot.control.isSteady()


def test_movel_and_movej_ik_end_at_their_poses(robot: Robot) -> None:
    pose = robot.receive.getActualTCPPose()
    goal = [pose[0] + 0.05, pose[1] - 0.03, pose[2] + 0.04, *pose[3:]]
    assert robot.control.moveL(goal, 0.25, 1.2)
    settle(robot)
    assert robot.receive.getActualTCPPose() == pytest.approx(goal, abs=METRE)
    back = [goal[0] - 0.02, goal[1] + 0.02, goal[2] - 0.02, *goal[3:]]
    assert robot.control.moveJ_IK(back, 1.05, 1.4)
    settle(robot)
    assert robot.receive.getActualTCPPose() == pytest.approx(back, abs=METRE)


def test_get_inverse_kinematics_gives_joints_whose_pose_is_the_one_asked(robot: Robot) -> None:
    pose = robot.receive.getActualTCPPose()
    goal = [pose[0], pose[1] + 0.05, pose[2], *pose[3:]]
    q = robot.control.getInverseKinematics(goal)
    assert kin.forward(arm_model("UR5e"), q) == pytest.approx(goal, abs=1e-6)
    assert np.linalg.norm(np.array(q) - robot.receive.getActualQ()) < 0.5  # the solution near the arm


def test_a_servoj_stream_at_500_hz_is_followed_to_its_last_target(robot: Robot) -> None:
    start = robot.receive.getActualQ()
    q = list(start)
    for i in range(500):
        period = robot.control.initPeriod()
        q = [start[0] + 0.0004 * i, *start[1:5], start[5] - 0.0004 * i]
        assert robot.control.servoJ(q, 0.5, 0.5, 0.002, 0.1, 300)
        robot.control.waitPeriod(period)
    # a loaded machine may hold the emulator's process back: the last target is reached late
    settle_until(lambda: robot.receive.getActualQ() == pytest.approx(q, abs=RAD))
    robot.control.servoStop()
    settle(robot)
    assert robot.receive.getActualQ() == pytest.approx(q, abs=RAD)


def test_speedj_moves_at_the_speed_and_stopj_stops_it(robot: Robot) -> None:
    start = robot.receive.getActualQ()
    assert robot.control.speedJ([0.2, 0, 0, 0, 0, -0.1], 1.0, 0.002)
    time.sleep(0.6)
    assert robot.receive.getActualQd() == pytest.approx([0.2, 0, 0, 0, 0, -0.1], abs=1e-6)
    robot.control.speedStop(2.0)
    settle(robot, 0.3)
    assert robot.receive.getActualQd() == pytest.approx([0.0] * 6, abs=1e-9)
    moved = np.array(robot.receive.getActualQ()) - np.array(start)
    assert moved[0] > 0.08 and moved[5] < -0.04 and abs(moved[1]) < 1e-9


def test_speedl_moves_the_tool_and_speed_stop_stops_it(robot: Robot) -> None:
    start = robot.receive.getActualTCPPose()
    assert robot.control.speedL([0.0, 0.0, 0.05, 0, 0, 0], 0.5, 0.002)
    time.sleep(0.6)
    assert robot.receive.getActualTCPSpeed()[2] == pytest.approx(0.05, abs=1e-4)
    robot.control.speedStop(2.0)
    settle(robot, 0.3)
    assert robot.receive.getActualTCPSpeed() == pytest.approx([0.0] * 6, abs=1e-9)
    pose = robot.receive.getActualTCPPose()
    assert pose[2] - start[2] > 0.015 and pose[:2] == pytest.approx(start[:2], abs=1e-4)


def test_an_async_movej_is_stopped_by_stopj(robot: Robot) -> None:
    start = robot.receive.getActualQ()
    target = [start[0] - 1.0, *start[1:]]
    assert robot.control.moveJ(target, 0.3, 0.5, True)  # asynchronous: returns at once
    time.sleep(0.4)
    assert not robot.control.isSteady()  # on its way
    robot.control.stopJ(2.0)
    settle(robot, 0.3)
    q = robot.receive.getActualQ()
    assert robot.receive.getActualQd() == pytest.approx([0.0] * 6, abs=1e-9)
    assert start[0] - 0.9 < q[0] < start[0] - 0.01  # stopped on the way
    assert robot.control.isSteady()


def test_an_async_movel_is_stopped_by_stopl(robot: Robot) -> None:
    start = robot.receive.getActualTCPPose()
    goal = [start[0], start[1], start[2] - 0.15, *start[3:]]
    assert robot.control.moveL(goal, 0.5, 0.1, True)
    time.sleep(0.5)
    robot.control.stopL(2.0)
    settle(robot, 0.3)
    pose = robot.receive.getActualTCPPose()
    assert robot.receive.getActualTCPSpeed() == pytest.approx([0.0] * 6, abs=1e-9)
    assert start[2] - 0.14 < pose[2] < start[2] - 0.01 and pose[:2] == pytest.approx(start[:2], abs=1e-4)


def test_set_tcp_and_set_payload_show_in_the_outputs(robot: Robot) -> None:
    tcp = [0.0, 0.0, 0.12, 0.0, 0.0, 0.0]
    assert robot.control.setTcp(tcp)
    assert robot.control.setPayload(1.5, [0.0, 0.01, 0.05])
    settle(robot)
    q = robot.receive.getActualQ()
    assert robot.receive.getActualTCPPose() == pytest.approx(kin.forward(arm_model("UR5e"), q, tcp), abs=1e-9)
    assert robot.receive.getPayload() == pytest.approx(1.5)
    assert robot.receive.getPayloadCog() == pytest.approx([0.0, 0.01, 0.05])
    assert robot.control.setTcp([0.0] * 6)
    flange = kin.forward(arm_model("UR5e"), q, [0.0] * 6)
    settle_until(lambda: robot.receive.getActualTCPPose() == pytest.approx(flange, abs=1e-9))
    # the next test reads the pose first: under load the outputs showed the 0.12 m TCP for a while


def test_force_mode_and_teach_mode_hold_the_arm_and_end(robot: Robot) -> None:
    q = robot.receive.getActualQ()
    pose = robot.receive.getActualTCPPose()
    assert control_mode(HOST) == POSITION
    assert robot.control.forceMode(
        [0.0] * 6, [0, 0, 1, 0, 0, 0], [0, 0, -2, 0, 0, 0], 2, [2, 2, 1.5, 1, 1, 1]
    )
    settle_until(lambda: control_mode(HOST) == FORCE)
    time.sleep(0.3)
    assert robot.control.forceModeStop()
    settle_until(lambda: control_mode(HOST) == POSITION)
    assert robot.control.teachMode()
    settle_until(lambda: control_mode(HOST) == TEACH)
    assert robot.control.endTeachMode()
    settle_until(lambda: control_mode(HOST) == POSITION)
    settle(robot)
    assert robot.receive.getActualTCPPose() == pytest.approx(pose, abs=1e-9)  # approximated: held still
    target = [q[0] + 0.05, *q[1:]]
    assert robot.control.moveJ(target)  # the script still takes commands
    settle(robot)
    assert robot.receive.getActualQ() == pytest.approx(target, abs=RAD)
    assert robot.control.isSteady()


def test_rtde_io_setters_show_in_the_outputs() -> None:
    host = "127.0.0.72"
    proc, _ = serve(host)
    try:
        io = rtde_io.RTDEIOInterface(host)
        receive = rtde_receive.RTDEReceiveInterface(host)
        try:
            assert io.setStandardDigitalOut(3, True) and io.setToolDigitalOut(1, True)
            assert io.setSpeedSlider(0.4)
            settle_until(lambda: receive.getActualDigitalOutputBits() == (1 << 3) | (1 << 17))
            assert receive.getTargetSpeedFraction() == pytest.approx(0.4)
            assert io.setStandardDigitalOut(3, False)
            settle_until(lambda: receive.getActualDigitalOutputBits() == 1 << 17)
            assert io.setConfigurableDigitalOut(2, True)
            settle_until(lambda: receive.getActualDigitalOutputBits() == (1 << 10) | (1 << 17))
            assert io.setAnalogOutputVoltage(0, 0.25) and io.setAnalogOutputCurrent(1, 0.75)
            settle_until(lambda: receive.getStandardAnalogOutput0() == pytest.approx(0.25))
            settle_until(lambda: receive.getStandardAnalogOutput1() == pytest.approx(0.75))
        finally:
            io.disconnect()
            receive.disconnect()
    finally:
        proc.terminate()
        proc.wait(10)


def test_trigger_protective_stop_stops_the_arm(robot: Robot) -> None:
    # last in the module: a protective stop ends the program, as on a robot
    assert robot.control.triggerProtectiveStop()
    settle_until(robot.receive.isProtectiveStopped)
    assert robot.receive.getSafetyMode() == 3  # PROTECTIVE_STOP
