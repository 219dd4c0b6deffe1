"""A simple dynamics model of the arm, for URScript's get_mass_matrix and
get_coriolis_and_centrifugal_torques: not the arm's real inertia (docs/decisions.md says why).

spec/arms holds the arms' kinematics but no masses, so each link is modelled as LINK_MASS kg at
the origin of its distal DH frame (the next joint, or the flange), a small sphere of LINK_INERTIA
kg m² about every axis; the active payload (set_target_payload: mass, centre of gravity from the
flange, inertia at the CoG in flange axes) rides on the flange, as a controller counts it. From
that the mass matrix M(q) = sum m Jv' Jv + Jw' I Jw is symmetric and positive definite and
changes with the pose as a real arm's does, and the Coriolis and centrifugal torques are this
model's exactly (Newton-Euler with no joint acceleration: each body's J' (m a, I alpha + w x I w)),
so the two agree (qd . c = qd . dM/dt qd / 2): client code built on them (computed torque,
impedance laws) runs on consistent numbers whose size is of the right order, not the robot's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.jacobian import frames, motion, point_jacobian
from rtde_spec.metamodel.arms import ArmModel

Matrix = NDArray[np.float64]
LINK_MASS = 1.0  # kg, every link (the model's unit: no arm's real mass)
LINK_INERTIA = 0.001  # kg m², every link about every axis (1 kg as a solid sphere of 5 cm radius)
# kg m² each joint's motor adds through its gear when include_rotors_inertia is asked: a round
# number of the size a harmonic drive reflects (~1e-5 kg m² of rotor times a ratio of ~100, squared)
ROTOR_INERTIA = (0.1, 0.1, 0.1, 0.1, 0.1, 0.1)
_MOVES = np.tril(np.ones((6, 6)))  # [link, joint]: 1 where the joint moves the link
_SHARED = _MOVES.T @ _MOVES  # [j, k]: how many links joints j and k both move


def _payload(
    flange: Matrix, origins: Matrix, cog: kin.Floats, inertia: kin.Floats | None
) -> tuple[Matrix, Matrix]:
    """The payload's centre of gravity in Base and its inertia there (Base axes)."""
    centre = origins[6] + flange @ np.array([float(v) for v in cog])
    if inertia is None or not any(inertia):
        return centre, np.zeros((3, 3))
    ixx, iyy, izz, ixy, ixz, iyz = (float(v) for v in inertia)
    local = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return centre, flange @ local @ flange.T


def _link_jacobians(axes: Matrix, origins: Matrix) -> Matrix:
    """[link, joint, xyz]: the velocity of each link's mass per joint velocity."""
    return np.cross(axes[None], origins[1:, None] - origins[None, :6]) * _MOVES[:, :, None]


def mass_matrix(
    arm: ArmModel,
    q: kin.Floats,
    payload: float = 0.0,
    cog: kin.Floats = (0.0, 0.0, 0.0),
    inertia: kin.Floats | None = None,
    rotors: bool = False,
) -> Matrix:
    """6 x 6 (kg m², joint space) at joints q; `inertia` is the payload's [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]."""
    axes, origins, flange = frames(arm, q)
    linear = _link_jacobians(axes, origins)
    out = LINK_MASS * np.einsum("lki,lji->kj", linear, linear) + LINK_INERTIA * (axes @ axes.T) * _SHARED
    if payload > 0:
        centre, turning = _payload(flange, origins, cog, inertia)
        jac = point_jacobian(axes, origins, centre)
        out += payload * jac[:3].T @ jac[:3] + jac[3:].T @ turning @ jac[3:]
    if rotors:
        out += np.diag(ROTOR_INERTIA)
    return np.asarray((out + out.T) / 2, dtype=np.float64)  # exactly symmetric


def coriolis_torques(
    arm: ArmModel,
    q: kin.Floats,
    qd: kin.Floats,
    payload: float = 0.0,
    cog: kin.Floats = (0.0, 0.0, 0.0),
    inertia: kin.Floats | None = None,
) -> Matrix:
    """The joint torques (N m) the model's Coriolis and centrifugal effects ask at joints q, speeds qd."""
    speeds = np.array([float(v) for v in qd])
    if not np.any(speeds):
        return np.zeros(6)
    axes, origins, flange = frames(arm, q)
    spin, origin_speed, axis_rate = motion(axes, origins, speeds)
    moving = _MOVES * speeds  # [link, joint]: the joint's speed where it moves the link
    # each link's mass (at origin l + 1) accelerates, with no joint acceleration, by
    # sum_k (axis_rate_k x (p - o_k) + z_k x (v_p - v_k)) qd_k
    offsets = origins[1:, None] - origins[None, :6]
    relative = origin_speed[1:, None] - origin_speed[None, :6]
    terms = np.cross(axis_rate[None], offsets) + np.cross(axes[None], relative)
    accel = np.einsum("lk,lki->li", moving, terms)
    out = LINK_MASS * np.einsum("lki,li->k", _link_jacobians(axes, origins), accel)
    turn_rate = moving @ axis_rate  # [link, xyz]: angular acceleration (isotropic: no w x I w)
    out += LINK_INERTIA * np.einsum("lk,ki,li->k", _MOVES, axes, turn_rate)
    if payload > 0:
        centre, turning = _payload(flange, origins, cog, inertia)
        jac = point_jacobian(axes, origins, centre)
        velocity = origin_speed[6] + np.cross(spin[6], centre - origins[6])
        parts = np.cross(axis_rate, centre - origins[:6]) + np.cross(axes, velocity - origin_speed[:6])
        out += payload * jac[:3].T @ (speeds @ parts)
        alpha, omega = speeds @ axis_rate, spin[6]
        out += jac[3:].T @ (turning @ alpha + np.cross(omega, turning @ omega))
    return np.asarray(out, dtype=np.float64)
