"""The arm's jacobian and its simple dynamics model (rtde_spec/emulator/arm/jacobian.py, dynamics.py).

The jacobian is held to a finite difference of forward kinematics: column j is how the TCP moves
(m/rad, then its rotation in rad/rad, in the Base frame) per radian of joint j, so J @ qd is the
TCP's velocity as `actual_TCP_speed` gives it. Its time derivative is held to a finite difference
of the jacobian along the joint speeds. The mass matrix is symmetric and positive definite, and
the Coriolis torques are the model's Lagrangian ones, c = dM/dt qd - d/dq (qd' M qd) / 2.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtde_spec.emulator.arm import dynamics, jacobian
from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.state import Arm
from rtde_spec.metamodel.arms import arm_model

H = 1e-6
POSES = [
    [0.0, -1.57, 1.57, -1.57, -1.57, 0.0],
    [0.3, -1.2, 1.1, -0.7, -1.4, 0.5],
    [-2.0, -0.4, -1.9, 2.2, 0.8, -3.0],
]
TCPS = [None, [0.01, -0.02, 0.15, 0.1, -0.2, 0.3]]


def numeric_jacobian(model: object, q: list[float], tcp: list[float] | None) -> np.ndarray:
    """Central differences of the TCP's frame: position and rotation per joint."""
    out = np.zeros((6, 6))
    for j in range(6):
        up, down = list(q), list(q)
        up[j] += H
        down[j] -= H
        r_up, p_up = kin.tcp_frame(model, up, tcp)  # type: ignore[arg-type]
        r_down, p_down = kin.tcp_frame(model, down, tcp)  # type: ignore[arg-type]
        out[:3, j] = (np.array(p_up) - np.array(p_down)) / (2 * H)
        out[3:, j] = np.array(kin.matrix_to_rotvec(kin.mul(r_up, kin.transpose(r_down)))) / (2 * H)
    return out


@pytest.mark.parametrize("name", ["UR5e", "UR10", "UR3e"])
@pytest.mark.parametrize("q", POSES)
@pytest.mark.parametrize("tcp", TCPS)
def test_the_jacobian_is_the_derivative_of_forward_kinematics(
    name: str, q: list[float], tcp: list[float] | None
) -> None:
    model = arm_model(name)
    assert jacobian.jacobian(model, q, tcp) == pytest.approx(numeric_jacobian(model, q, tcp), abs=1e-7)


def test_the_jacobian_times_the_joint_speeds_is_the_tcp_speed_the_arm_reports() -> None:
    model = arm_model("UR5e")
    arm = Arm(model, POSES[1])
    arm.tcp = tuple(TCPS[1])  # type: ignore[arg-type]
    arm.state.qd = np.array([0.2, -0.1, 0.3, 0.05, -0.4, 0.6])
    expected = jacobian.jacobian(model, arm.state.q, arm.tcp) @ arm.state.qd
    assert arm.tcp_speed() == pytest.approx(expected, abs=1e-3)  # (tcp_speed is a 0.1 ms difference)


@pytest.mark.parametrize("q", POSES)
def test_the_time_derivative_is_the_jacobians_change_along_the_joint_speeds(q: list[float]) -> None:
    model = arm_model("UR5e")
    qd = np.array([0.4, -0.3, 0.2, 0.7, -0.5, 1.1])
    h = 1e-6
    ahead = jacobian.jacobian(model, np.array(q) + qd * h, TCPS[1])
    behind = jacobian.jacobian(model, np.array(q) - qd * h, TCPS[1])
    numeric = (ahead - behind) / (2 * h)
    assert jacobian.jacobian_derivative(model, q, qd, TCPS[1]) == pytest.approx(numeric, abs=1e-7)
    assert np.all(jacobian.jacobian_derivative(model, q, np.zeros(6)) == 0)  # still: no change


@pytest.mark.parametrize("q", POSES)
def test_the_mass_matrix_is_symmetric_positive_definite_and_takes_the_payload(q: list[float]) -> None:
    model = arm_model("UR5e")
    m = dynamics.mass_matrix(model, q)
    assert m == pytest.approx(m.T, abs=1e-12)
    assert np.all(np.linalg.eigvalsh(m) > 0)
    loaded = dynamics.mass_matrix(model, q, 5.0, [0.0, 0.0, 0.1])
    assert np.all(np.linalg.eigvalsh(loaded - m) >= -1e-12) and loaded[0, 0] > m[0, 0]  # only heavier
    rotors = dynamics.mass_matrix(model, q, rotors=True)
    assert rotors - m == pytest.approx(np.diag(dynamics.ROTOR_INERTIA), abs=1e-12)


@pytest.mark.parametrize("q", POSES)
@pytest.mark.parametrize("inertia", [None, [0.1, 0.2, 0.3, 0.01, 0.02, 0.03]])
def test_coriolis_torques_are_the_models_lagrangian_ones(q: list[float], inertia: list[float] | None) -> None:
    """c = dM/dt qd - d/dq (qd' M qd) / 2, both sides from the model's mass matrix (central differences)."""
    model, here = arm_model("UR5e"), np.array(q)
    qd = np.array([0.4, -0.3, 0.2, 0.7, -0.5, 1.1])
    load = (2.0, [0.0, 0.02, 0.05], inertia)

    def mass(at: np.ndarray) -> np.ndarray:
        return dynamics.mass_matrix(model, at, *load)

    m_dot = (mass(here + qd * H) - mass(here - qd * H)) / (2 * H)
    gradient = [qd @ (mass(here + step) - mass(here - step)) @ qd / (2 * H) for step in np.eye(6) * H]
    c = dynamics.coriolis_torques(model, q, qd, *load)
    assert c == pytest.approx(m_dot @ qd - np.array(gradient) / 2, abs=1e-7)
    assert float(qd @ c) == pytest.approx(0.5 * float(qd @ m_dot @ qd), rel=1e-6)  # power balance
    assert dynamics.coriolis_torques(model, q, 2 * qd, *load) == pytest.approx(4 * c)  # quadratic
    assert np.all(dynamics.coriolis_torques(model, q, np.zeros(6)) == 0)
    assert not math.isclose(float(np.linalg.norm(c)), 0.0)
