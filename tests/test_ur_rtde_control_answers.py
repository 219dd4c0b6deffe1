"""ur_rtde's getJointTorques and toolContact against the emulator: what a controller answers, and when
ur_rtde can see it.

ur_rtde (1.6.5, its `RTDEControlInterface::sendCommand`) sends the commands it counts as real-time
(servoing and speeding, force mode, the watchdog, getJointTorques, toolContact, getStepTime,
getActualJointPositionsHistory, getActualToolFlangePose, ...) once output_int_register_0 says the
script is ready (1) and returns at once: it does not wait for "done" (2), nor, unlike getJacobian
and getMassMatrix, for a newer package. getJointTorques then reads output_double_register_0..5 and
toolContact output_int_register_1 from the package its receive thread last stored, one that left
the controller before the command did. Straight after getTCPOffset (or isPoseWithinSafetyLimits)
those registers still hold that call's answer, on a robot as here: no controller can answer a
command in a package it sent before the command came. ur_rtde's script does these commands in
every cycle while the input register holds them (ur_rtde sends no "clear" after them), so every
package computed after the command carries the answer, and the next call reads it.

So each try here asks once right after the call that filled the registers (its answer must be one
of the two, never a mix), waits for the packages after the command (the receive interface's
timestamps), and asks again: that first ask must be right. The 3.14 control script has no
tool_contact (its lines are for 5.4 and later: ur_rtde leaves them out for older controllers), so
there toolContact keeps whatever the previous command wrote in the register, as on a CB3.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from rtde_spec.metamodel.catalogue import Catalogue

from .ur_rtde_robot import Robot, settle_until, ur_rtde_robot

rtde_control = pytest.importorskip("rtde_control", reason="ur_rtde is installed by the test extra")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")

HOST = "127.0.0.78"
TRIES = 15
OFFSET = [0.01, 0.02, 0.15, 0.0, 0.0, 0.1]  # a TCP offset no joint torque at rest looks like
TORQUES = [0.0] * 6  # get_joint_torques() of the emulated arm, which models no motor torques
DOWN = [0.0, 0.0, -0.1, 0.0, 0.0, 0.0]  # the direction toolContact watches
# s of controller time: the control interface stores its packages on a receive thread of its own,
# which on a loaded machine ran a few ms behind the receive interface's (4 steps at 500 Hz, 7 ms,
# were seen with the control interface still holding the package from before the command, and 1 ms
# later the answer); an emulator that never answers, or answers once and not in every later
# package, still fails
LAG = 0.05
pytestmark = [
    pytest.mark.slow,
    pytest.mark.xdist_group("ur-rtde-control-answers"),
    pytest.mark.fixed_ports(HOST),
]


@pytest.fixture(scope="module", params=[("5.15.0", "UR5e"), ("3.14.3", "UR5")], ids=lambda p: p[0])
def robot(request: pytest.FixtureRequest) -> Iterator[Robot]:
    controller, model = request.param
    with ur_rtde_robot(HOST, rtde_control, rtde_receive, controller, model) as robot:
        assert robot.control.setTcp(OFFSET)
        yield robot


def after_the_command(robot: Robot, steps: int = 4) -> None:
    """Return once the receive interface holds a package `steps` control steps newer than the one it
    held when called (`LAG` s at least): computed after the command just sent, as the control
    interface's are by then."""
    period = 1.0 / Catalogue.default().line_of(robot.controller).rtde_max_frequency
    start = robot.receive.getTimestamp()
    newer = start + max((steps - 0.5) * period, LAG)
    settle_until(lambda: robot.receive.getTimestamp() > newer, 5.0, "no packages came")


def test_get_joint_torques_after_get_tcp_offset_is_the_torques_once_a_package_came(robot: Robot) -> None:
    later = []
    for _ in range(TRIES):
        assert robot.control.getTCPOffset() == pytest.approx(OFFSET, abs=1e-12)
        at_once = robot.control.getJointTorques()  # the package ur_rtde held: the offset, as on a robot
        assert at_once in (pytest.approx(OFFSET, abs=1e-12), pytest.approx(TORQUES, abs=1e-12)), at_once
        after_the_command(robot)
        later.append(robot.control.getJointTorques())
    assert later == [pytest.approx(TORQUES, abs=1e-12)] * TRIES


def test_tool_contact_after_another_answer_is_its_own_once_a_package_came(robot: Robot) -> None:
    pose = robot.receive.getActualTCPPose()
    # no contact (0) from 5.4 on; the 3.14 script has no tool_contact: the register keeps the 1
    expected = 0 if robot.controller.startswith("5.") else 1
    later = []
    for _ in range(TRIES):
        assert robot.control.isPoseWithinSafetyLimits(pose)  # output_int_register_1 = 1
        assert robot.control.toolContact(DOWN) in (0, 1)  # the package ur_rtde held: 1, as on a robot
        after_the_command(robot)
        later.append(robot.control.toolContact(DOWN))
    assert later == [expected] * TRIES
