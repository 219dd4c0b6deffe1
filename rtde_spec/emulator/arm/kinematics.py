"""Forward and inverse kinematics of a UR arm from its nominal DH rows (spec/arms/models.yaml).

Poses are UR's: [x, y, z, rx, ry, rz] in the Base frame, m and a rotation vector
(axis times angle, angle in [0, pi]) — what actual_TCP_pose and `p[...]` hold.
The inverse is closed form for the UR geometry (joints 2-4 parallel, a wrist whose
axes meet pairwise): up to 8 solutions, 2 shoulder x 2 wrist x 2 elbow, of which
`nearest` picks the one closest to the current joints, each joint moved by a whole
turn where that brings it closer.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from rtde_spec.errors import UsageError
from rtde_spec.metamodel.arms import ArmModel

Matrix = NDArray[np.float64]
Floats = Sequence[float] | NDArray[np.float64]  # a list, a tuple or a numpy vector
Pose = tuple[float, float, float, float, float, float]
Joints = tuple[float, float, float, float, float, float]
EPS = 1e-9
TWO_PI = 2 * math.pi


Rot = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]
Vec3 = tuple[float, float, float]


def dh_matrix(theta: float, d: float, a: float, alpha: float) -> Matrix:
    """One standard DH row: Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def flange_frame(arm: ArmModel, q: Floats) -> tuple[Rot, Vec3]:
    """Base -> flange (rotation, position) in closed form for UR rows (alpha pi/2, 0, 0, pi/2, -pi/2, 0).

    Plain float arithmetic: at 500 Hz a handful of numpy 4x4 products costs more than this.
    """
    d1, d4, d5, d6 = arm.dh.d[0], arm.dh.d[3], arm.dh.d[4], arm.dh.d[5]
    a2, a3 = arm.dh.a[1], arm.dh.a[2]
    q1, q2, q3, q4, q5, q6 = (float(v) for v in q)
    s1, c1, s2, c2 = math.sin(q1), math.cos(q1), math.sin(q2), math.cos(q2)
    s5, c5, s6, c6 = math.sin(q5), math.cos(q5), math.sin(q6), math.cos(q6)
    s23, c23 = math.sin(q2 + q3), math.cos(q2 + q3)
    s234, c234 = math.sin(q2 + q3 + q4), math.cos(q2 + q3 + q4)
    u, w = c1 * c234 * c5 + s1 * s5, -c1 * s5 + c234 * c5 * s1
    rot = (
        (-c1 * s234 * s6 + c6 * u, -c1 * c6 * s234 - s6 * u, -c1 * c234 * s5 + c5 * s1),
        (c6 * w - s1 * s234 * s6, -c6 * s1 * s234 - s6 * w, -c1 * c5 - c234 * s1 * s5),
        (c234 * s6 + c5 * c6 * s234, c234 * c6 - c5 * s234 * s6, -s234 * s5),
    )
    reach = a2 * c2 + a3 * c23 - c234 * d6 * s5 + d5 * s234
    pos = (
        c1 * reach + c5 * d6 * s1 + d4 * s1,
        s1 * reach - c1 * c5 * d6 - c1 * d4,
        a2 * s2 + a3 * s23 - c234 * d5 + d1 - d6 * s234 * s5,
    )
    return rot, pos


def mul(a: Rot, b: Rot) -> Rot:
    return tuple(  # type: ignore[return-value]
        tuple(a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j] for j in range(3)) for i in range(3)
    )


def apply(a: Rot, v: Floats) -> Vec3:
    return (
        a[0][0] * v[0] + a[0][1] * v[1] + a[0][2] * v[2],
        a[1][0] * v[0] + a[1][1] * v[1] + a[1][2] * v[2],
        a[2][0] * v[0] + a[2][1] * v[1] + a[2][2] * v[2],
    )


def transpose(a: Rot) -> Rot:
    return ((a[0][0], a[1][0], a[2][0]), (a[0][1], a[1][1], a[2][1]), (a[0][2], a[1][2], a[2][2]))


def rotvec_to_rot(rv: Floats) -> Rot:
    """Rodrigues: rotation vector -> rotation matrix (nested tuples)."""
    x, y, z = float(rv[0]), float(rv[1]), float(rv[2])
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < EPS:
        return ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    x, y, z = x / angle, y / angle, z / angle
    c, s = math.cos(angle), math.sin(angle)
    t = 1 - c
    return (
        (c + x * x * t, x * y * t - z * s, x * z * t + y * s),
        (y * x * t + z * s, c + y * y * t, y * z * t - x * s),
        (z * x * t - y * s, z * y * t + x * s, c + z * z * t),
    )


def rotvec_to_matrix(rv: Floats) -> Matrix:
    return np.array(rotvec_to_rot(rv))


def matrix_to_rotvec(r: Sequence[Sequence[float]] | Matrix) -> Vec3:
    """Rotation matrix -> rotation vector with angle in [0, pi], via a unit quaternion."""
    r00, r01, r02 = float(r[0][0]), float(r[0][1]), float(r[0][2])
    r10, r11, r12 = float(r[1][0]), float(r[1][1]), float(r[1][2])
    r20, r21, r22 = float(r[2][0]), float(r[2][1]), float(r[2][2])
    trace = r00 + r11 + r22
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        w, x, y, z = 0.25 * s, (r21 - r12) / s, (r02 - r20) / s, (r10 - r01) / s
    elif r00 > r11 and r00 > r22:
        s = math.sqrt(1.0 + r00 - r11 - r22) * 2
        w, x, y, z = (r21 - r12) / s, 0.25 * s, (r01 + r10) / s, (r02 + r20) / s
    elif r11 > r22:
        s = math.sqrt(1.0 + r11 - r00 - r22) * 2
        w, x, y, z = (r02 - r20) / s, (r01 + r10) / s, 0.25 * s, (r12 + r21) / s
    else:
        s = math.sqrt(1.0 + r22 - r00 - r11) * 2
        w, x, y, z = (r10 - r01) / s, (r02 + r20) / s, (r12 + r21) / s, 0.25 * s
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    norm = math.sqrt(x * x + y * y + z * z)
    if norm < EPS:
        return (0.0, 0.0, 0.0)
    angle = 2 * math.atan2(norm, w)
    return (x / norm * angle, y / norm * angle, z / norm * angle)


def pose_to_matrix(pose: Floats) -> Matrix:
    t = np.eye(4)
    t[:3, :3] = rotvec_to_rot(pose[3:6])
    t[:3, 3] = [float(v) for v in pose[:3]]
    return t


def matrix_to_pose(t: Matrix) -> Pose:
    rx, ry, rz = matrix_to_rotvec(t[:3, :3])
    return (float(t[0, 3]), float(t[1, 3]), float(t[2, 3]), rx, ry, rz)


def tcp_frame(arm: ArmModel, q: Floats, tcp: Floats | None = None) -> tuple[Rot, Vec3]:
    """Base -> TCP (rotation, position): the flange moved by the `tcp` offset."""
    rot, pos = flange_frame(arm, q)
    if tcp is not None and any(tcp):
        offset = apply(rot, tcp[:3])
        pos = (pos[0] + offset[0], pos[1] + offset[1], pos[2] + offset[2])
        rot = mul(rot, rotvec_to_rot(tcp[3:6]))
    return rot, pos


def forward(arm: ArmModel, q: Floats, tcp: Floats | None = None) -> Pose:
    """The TCP pose at joints q, with `tcp` the flange -> TCP offset (zero by default)."""
    rot, pos = tcp_frame(arm, q, tcp)
    return (pos[0], pos[1], pos[2], *matrix_to_rotvec(rot))


def inverse_all(
    arm: ArmModel, pose: Floats, tcp: Floats | None = None, q6: float = 0.0, branch: Floats | None = None
) -> list[Joints]:
    """Every closed-form solution (up to 8) reaching `pose`; q6 is used where wrist 3 is free.

    With `branch` (joints), only the solution of the same shoulder, elbow and wrist
    configuration is computed: what a straight-line move needs every control step.
    """
    rot = rotvec_to_rot(pose[3:6])
    p6: Sequence[float] = [float(v) for v in pose[:3]]
    if tcp is not None and any(tcp):  # the flange is the TCP less its offset
        rot = mul(rot, transpose(rotvec_to_rot(tcp[3:6])))
        back = apply(rot, tcp[:3])
        p6 = [p6[0] - back[0], p6[1] - back[1], p6[2] - back[2]]
    d1, d4, d5, d6 = arm.dh.d[0], arm.dh.d[3], arm.dh.d[4], arm.dh.d[5]
    a2, a3 = arm.dh.a[1], arm.dh.a[2]
    p5 = [p6[i] - d6 * rot[i][2] for i in range(3)]  # wrist 2 centre
    r = math.hypot(p5[0], p5[1])
    if r < abs(d4) - EPS:
        return []
    psi = math.atan2(p5[1], p5[0])
    phi = math.asin(max(-1.0, min(1.0, d4 / r)))
    out: list[Joints] = []
    shoulders = [psi + phi, psi + math.pi - phi]  # from p5 . z1 = d4, z1 = (sin t1, -cos t1, 0)
    wrist = elbow = 0
    if branch is not None:
        shoulders.sort(key=lambda t: abs(_wrap(t - float(branch[0]))))
        del shoulders[1:]
        wrist, elbow = _sign(_wrap(float(branch[4]))), _sign(_wrap(float(branch[2])))
    for t1 in shoulders:
        s1, c1 = math.sin(t1), math.cos(t1)
        # the target in frame 1: x' = c1 x + s1 y, y' = z (- d1), z' = s1 x - c1 y
        r16 = tuple(
            (c1 * rot[0][j] + s1 * rot[1][j], rot[2][j], s1 * rot[0][j] - c1 * rot[1][j]) for j in range(3)
        )  # columns
        p16 = (c1 * p6[0] + s1 * p6[1], p6[2] - d1, s1 * p6[0] - c1 * p6[1])
        c5 = (p16[2] - d4) / d6
        if abs(c5) > 1 + 1e-7:
            continue
        base5 = math.acos(max(-1.0, min(1.0, c5)))
        for t5 in (base5, -base5) if wrist == 0 else (wrist * base5,):
            s5, c5 = math.sin(t5), math.cos(t5)
            # row z of R16 is (s5 c6, -s5 s6, c5)
            t6 = q6 if abs(s5) < 1e-6 else math.atan2(-r16[1][2] / s5, r16[0][2] / s5)
            s6, c6 = math.sin(t6), math.cos(t6)
            v = (-s6 * d5, -c6 * d5, d6)  # flange -> frame 4 origin, in frame 6
            x4 = (c5 * c6, -c5 * s6, -s5)  # frame 4's x axis, in frame 6
            x = p16[0] - sum(r16[k][0] * v[k] for k in range(3))
            y = p16[1] - sum(r16[k][1] * v[k] for k in range(3))
            t234 = math.atan2(
                sum(r16[k][1] * x4[k] for k in range(3)), sum(r16[k][0] * x4[k] for k in range(3))
            )
            c3 = (x * x + y * y - a2 * a2 - a3 * a3) / (2 * a2 * a3)
            if abs(c3) > 1 + 1e-7:
                continue
            base3 = math.acos(max(-1.0, min(1.0, c3)))
            for t3 in (base3, -base3) if elbow == 0 else (elbow * base3,):
                t2 = math.atan2(y, x) - math.atan2(a3 * math.sin(t3), a2 + a3 * math.cos(t3))
                t4 = t234 - t2 - t3
                out.append((_wrap(t1), _wrap(t2), _wrap(t3), _wrap(t4), _wrap(t5), _wrap(t6)))
    return out


def nearest(
    arm: ArmModel, pose: Floats, current: Floats, tcp: Floats | None = None, same_branch: bool = False
) -> Joints:
    """The solution closest to `current` (each joint shifted by whole turns within its range).

    Closest means the smallest largest joint move; `same_branch` tries the current
    arm configuration first (a path followed in small steps). UsageError when the pose is out of
    reach, as a controller refuses it.
    """
    here = [float(v) for v in current]
    solutions = inverse_all(arm, pose, tcp, q6=here[5], branch=here) if same_branch else []
    solutions = solutions or inverse_all(arm, pose, tcp, q6=here[5])
    if not solutions:
        raise UsageError(f"pose {list(pose)} is out of reach of the {arm.name}", subject="inverse kinematics")
    limits = arm.joint_limits
    best: list[float] = []
    best_cost = math.inf
    for sol in solutions:
        moved, cost = [], 0.0
        for v, c, (low, high) in zip(sol, here, limits, strict=True):
            shifted = c + ((v - c + math.pi) % TWO_PI - math.pi)
            if shifted > high:
                shifted -= TWO_PI
            elif shifted < low:
                shifted += TWO_PI
            moved.append(shifted)
            cost = max(cost, abs(shifted - c))
        if cost < best_cost:
            best, best_cost = moved, cost
    return (best[0], best[1], best[2], best[3], best[4], best[5])


def _wrap(angle: float) -> float:
    """Into [-pi, pi)."""
    return (angle + math.pi) % TWO_PI - math.pi


def _sign(value: float) -> int:
    return -1 if value < 0 else 1
