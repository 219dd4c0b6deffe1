"""ur_rtde's RTDEControlInterface (pip ur_rtde) against controllers of 5.23 and later, whose control
script reads the arm's model: `get_jacobian()`, `get_mass_matrix()` and the rest, read out as
`jacobian[i, j]` (URScript's matrix subscript), and for 5.26 `direct_torque(...)`.

Before the emulator read `m[i, j]` and knew these functions, ur_rtde could not start at all against
`--controller 5.23.0` or later (its script was refused: "syntax_error_on_line:1101"). Each value
ur_rtde reads back is held to what the emulator's arm model computes for the arm's joints; ur_rtde
writes a 6x6 matrix column by column (`m[0, 0], m[1, 0], ...`), so its 36 numbers are column-major.

ur_rtde sends these commands without waiting for the script to finish them. getJacobian,
getMassMatrix, getCoriolisAndCentrifugalTorques and getJacobianTimeDerivative then wait for a
package one control step newer than the one they held and read the output registers there;
getTargetJointAccelerations reads them at once, from a package that left before the command did
(its first answer is the previous call's registers, on a robot too; see
tests/test_ur_rtde_control_answers.py). The emulator reads a step's inputs just before the step is
due (server/loop.py; tests/test_emulator_step_inputs.py asks once), but a command that comes while the
step is computed is answered one package later than ur_rtde looks (on a robot it races too), and
on a loaded machine the interpreter may not finish the 36 register writes in one step; so each
answer is asked again until it comes, within `ANSWER` s.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from rtde_spec.emulator.arm import dynamics, jacobian
from rtde_spec.metamodel.arms import arm_model

from .ur_rtde_robot import Robot, control_mode, settle_until, ur_rtde_robot

rtde_control = pytest.importorskip("rtde_control", reason="ur_rtde is installed by the test extra")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")

HOST, TORQUE_HOST = "127.0.0.74", "127.0.0.75"
RAD = 1e-4
ANSWER = 2.0  # s for ur_rtde's answer to show what the emulator computed
TORQUE = 3  # the Robot Mode Data's control mode
UR5E = arm_model("UR5e")
pytestmark = [
    pytest.mark.slow,
    pytest.mark.xdist_group("ur-rtde-control-dynamics"),
    pytest.mark.fixed_ports(HOST, TORQUE_HOST),
]


# 5.23 brings the model functions; 5.26's script adds direct_torque (ur_rtde's `$5.26` lines)
@pytest.fixture(scope="module", params=["5.23.0", "5.26.0"])
def robot(request: pytest.FixtureRequest) -> Iterator[Robot]:
    with ur_rtde_robot(HOST, rtde_control, rtde_receive, controller=request.param) as robot:
        yield robot


def column_major(matrix: np.ndarray) -> list[float]:
    """The 36 numbers as ur_rtde's script writes them: down each column, column after column."""
    return [float(v) for v in matrix.flatten(order="F")]


def answers(call: Callable[[], list[float]], expected: list[float], within: float = 1e-9) -> list[float]:
    """ur_rtde's answer once it is `expected` (see the module's docstring); fails with the last one."""
    deadline = time.monotonic() + ANSWER
    while True:
        got = list(call())
        if got == pytest.approx(expected, abs=within) or time.monotonic() > deadline:
            assert got == pytest.approx(expected, abs=within)
            return got
        time.sleep(0.01)


def test_the_control_script_starts_and_movej_ends_at_its_target(robot: Robot) -> None:
    assert robot.control.isConnected() and robot.control.isProgramRunning()
    q = robot.receive.getActualQ()
    target = [q[0] + 0.2, q[1] - 0.1, q[2] + 0.1, q[3], q[4], q[5] + 0.3]
    assert robot.control.moveJ(target, 1.05, 1.4)
    time.sleep(0.1)
    assert robot.receive.getActualQ() == pytest.approx(target, abs=RAD)


def test_get_jacobian_is_the_arms_at_its_joints(robot: Robot) -> None:
    q = robot.receive.getActualQ()
    expected = jacobian.jacobian(UR5E, q)
    answers(robot.control.getJacobian, column_major(expected))
    # the TCP's velocity per joint velocity: the top rows reach (m/rad), the bottom ones turn (1)
    assert np.linalg.norm(expected[3:], axis=0) == pytest.approx([1.0] * 6)


def test_get_mass_matrix_and_coriolis_torques_are_the_emulators_model(robot: Robot) -> None:
    q = robot.receive.getActualQ()
    payload, cog = robot.receive.getPayload(), robot.receive.getPayloadCog()
    expected = dynamics.mass_matrix(UR5E, q, payload, cog)
    got = answers(robot.control.getMassMatrix, column_major(expected))
    assert np.all(np.linalg.eigvalsh(np.reshape(got, (6, 6))) > 0)  # a mass matrix: positive definite
    # at rest no joint moves: no Coriolis or centrifugal torque, and the jacobian does not change
    answers(robot.control.getCoriolisAndCentrifugalTorques, [0.0] * 6, within=1e-12)
    answers(robot.control.getJacobianTimeDerivative, [0.0] * 36, within=1e-12)


def test_target_joint_accelerations_are_the_motions(robot: Robot) -> None:
    answers(robot.control.getTargetJointAccelerations, [0.0] * 6, within=1e-12)  # still
    q = robot.receive.getActualQ()
    target = [q[0] - 3.0, *q[1:]]
    # asynchronous: 5 s speeding up at 0.1 rad/s², time for the answers on a loaded machine (with
    # 0.6 rad at 0.25 rad/s² the window was 1.5 s, and a run under load missed it)
    assert robot.control.moveJ(target, 0.5, 0.1, True)
    qdd = answers(robot.control.getTargetJointAccelerations, [-0.1, 0.0, 0.0, 0.0, 0.0, 0.0], within=1e-6)
    assert robot.receive.getTargetQdd() == pytest.approx(qdd, abs=1e-6)  # as RTDE's target_qdd shows
    before = robot.control.getAsyncOperationProgressEx()
    robot.control.stopJ(2.0)  # returns nothing: whether it reached the script shows in the status
    deadline = time.monotonic() + 5.0
    while robot.control.getAsyncOperationProgress() >= 0:
        if time.monotonic() > deadline:  # once in CI (2026-11-26): say what it was, if it comes again
            now = robot.control.getAsyncOperationProgressEx()
            pytest.fail(
                "the asynchronous moveJ did not end after stopJ: the script wrote its status "
                f"{before.changeCount()} times before stopJ and {now.changeCount()} after (running: "
                f"{now.isAsyncOperationRunning()}); joint speeds {robot.receive.getActualQd()}"
            )
        time.sleep(0.01)


@pytest.fixture(scope="module")
def torque_robot() -> Iterator[Robot]:
    """5.26: the first version whose ur_rtde script calls direct_torque (its own host: the other
    fixture's emulator may still hold the controller's ports)."""
    with ur_rtde_robot(TORQUE_HOST, rtde_control, rtde_receive, controller="5.26.0") as robot:
        yield robot


def test_direct_torque_holds_the_arm_and_the_script_runs_on(torque_robot: Robot) -> None:
    robot = torque_robot
    here = robot.receive.getActualQ()
    for _ in range(50):  # a torque stream, one command a control step or so
        assert robot.control.directTorque([0.0, 0.0, 0.0, 0.0, 0.0, 0.5])
        time.sleep(0.002)
    # ur_rtde's script calls direct_torque once a step (it takes the step: no sync after it) for as
    # long as the command stands: torque control, the Robot Mode Data says
    settle_until(lambda: control_mode(TORQUE_HOST) == TORQUE)
    assert robot.control.isProgramRunning()
    assert robot.receive.getActualQ() == pytest.approx(here, abs=1e-9)  # no dynamics: the arm holds
