"""The arm's jacobian from its DH rows: how the TCP moves per joint velocity, and how that changes.

Column j is joint j's share of the TCP's velocity in the Base frame, rows 0-2 linear (m/s per
rad/s), rows 3-5 angular (rad/s per rad/s): the order of UR's TCP speeds (actual_TCP_speed,
speedl's xd), so J @ qd is the TCP speed the arm reports. It is the geometric jacobian: joint j
turns about z_j, the z axis of DH frame j (the Base's for j = 0), through that frame's origin o_j,
so column j is [z_j x (p - o_j), z_j] with p the TCP. Its time derivative along the joint speeds
is exact too (each axis turns with the links before it), not a difference quotient. Whole arrays
at a time: a program may ask for these every control step (ur_rtde reads 36 numbers in one).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.metamodel.arms import ArmModel

Matrix = NDArray[np.float64]


def frames(arm: ArmModel, q: kin.Floats) -> tuple[Matrix, Matrix, Matrix]:
    """Axes z_0..z_5 and origins o_0..o_6 of the DH frames (rows), and the flange's rotation."""
    t = np.eye(4)
    axes, origins = np.zeros((6, 3)), np.zeros((7, 3))
    for j in range(6):
        axes[j], origins[j] = t[:3, 2], t[:3, 3]
        t = t @ kin.dh_matrix(float(q[j]), arm.dh.d[j], arm.dh.a[j], arm.dh.alpha[j])
    origins[6] = t[:3, 3]
    return axes, origins, t[:3, :3]


def motion(axes: Matrix, origins: Matrix, speeds: Matrix) -> tuple[Matrix, Matrix, Matrix]:
    """At joint speeds `speeds`: each frame's angular velocity (frame k turns with joints 0..k-1),
    each frame origin's velocity, and how fast each joint axis turns (rows)."""
    spin, origin_speed = np.zeros((7, 3)), np.zeros((7, 3))
    spin[1:] = np.cumsum(axes * speeds[:, None], axis=0)
    origin_speed[1:] = np.cumsum(np.cross(spin[1:], origins[1:] - origins[:-1]), axis=0)
    return spin, origin_speed, np.cross(spin[:6], axes)


def tcp_point(origins: Matrix, flange: Matrix, tcp: kin.Floats | None) -> Matrix:
    """The TCP's position: the flange's origin moved by the TCP offset (in flange axes)."""
    if tcp is None:
        return origins[6].copy()
    return origins[6] + flange @ np.array([float(v) for v in tcp[:3]])


def point_jacobian(axes: Matrix, origins: Matrix, point: Matrix, joints: int = 6) -> Matrix:
    """6 x 6: the velocity of `point` (on the link after joint `joints - 1`) and that link's
    angular velocity per joint velocity; joints past it move neither (zero columns)."""
    out = np.zeros((6, 6))
    out[:3, :joints] = np.cross(axes[:joints], point - origins[:joints]).T
    out[3:, :joints] = axes[:joints].T
    return out


def jacobian(arm: ArmModel, q: kin.Floats, tcp: kin.Floats | None = None) -> Matrix:
    """6 x 6: the TCP's velocity (m/s, then rad/s, in Base) per joint velocity at joints q."""
    axes, origins, flange = frames(arm, q)
    return point_jacobian(axes, origins, tcp_point(origins, flange, tcp))


def jacobian_derivative(
    arm: ArmModel, q: kin.Floats, qd: kin.Floats, tcp: kin.Floats | None = None
) -> Matrix:
    """6 x 6: d/dt of `jacobian` while the joints move at qd (zero when they stand still)."""
    speeds = np.array([float(v) for v in qd])
    out = np.zeros((6, 6))
    if not np.any(speeds):
        return out
    axes, origins, flange = frames(arm, q)
    point = tcp_point(origins, flange, tcp)
    spin, origin_speed, axis_rate = motion(axes, origins, speeds)
    point_speed = origin_speed[6] + np.cross(spin[6], point - origins[6])
    out[:3] = (np.cross(axis_rate, point - origins[:6]) + np.cross(axes, point_speed - origin_speed[:6])).T
    out[3:] = axis_rate.T
    return out
