"""The pose maths a program calls for a value: differences, distances and interpolation of poses,
the rotation vector in roll-pitch-yaw and back, `size` of an array or matrix, and an int's 32 bits
as a list of bools and back. Poses compose
as 4x4 matrices (kinematics' pose_to_matrix), as pose_trans and pose_inv do in calls.py, so every
pose function agrees with the others to the last digit.

RPY is the Script Manual's (rotvec2rpy, rpy2rotvec; 5.21 and 10.7 editions): extrinsic rotations
about X, Y, Z, R = Rz(yaw) Ry(pitch) Rx(roll), in radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.urscript import matrices
from rtde_spec.emulator.urscript.calls import Pose, arg, number, six, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
Builtin = Callable[[Runner, Stmt, Args, Kwargs], Any]
POSES: dict[str, Builtin] = {}


_builtin = registrar(POSES)


def _pose(stmt: Stmt, value: Any) -> np.ndarray:
    return kin.pose_to_matrix(six(stmt, value, "pose"))


def _three(stmt: Stmt, value: Any, name: str) -> list[float]:
    if not isinstance(value, list) or len(value) != 3:
        raise ScriptFault(f"{stmt.name}: {name} must be three numbers", stmt.line, stmt.column or 1)
    return [number(stmt, v, name) for v in value]


@_builtin("tool_pose")
def _tool_pose(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    """PolyScope's Force node's task frame for its Tool feature: where the TCP is."""
    return Pose(runner.robot.arm.pose())


@_builtin("pose_sub")
def _pose_sub(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    a, b = _pose(stmt, args[0]), _pose(stmt, args[1])
    out = np.eye(4)
    out[:3, 3] = a[:3, 3] - b[:3, 3]
    out[:3, :3] = a[:3, :3] @ b[:3, :3].T
    return Pose(kin.matrix_to_pose(out))


@_builtin("pose_dist", "point_dist")
def _pose_dist(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    a, b = six(stmt, args[0], "p_from"), six(stmt, args[1], "p_to")
    return math.dist(a[:3], b[:3])


@_builtin("interpolate_pose")
def _interpolate(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    a, b = _pose(stmt, args[0]), _pose(stmt, args[1])
    alpha = number(stmt, args[2], "alpha")
    relative = a[:3, :3].T @ b[:3, :3]
    vector = np.array(
        kin.matrix_to_pose(np.block([[relative, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]))[3:]
    )
    turn = kin.pose_to_matrix([0, 0, 0, *(vector * alpha)])[:3, :3]
    out = np.eye(4)
    out[:3, 3] = a[:3, 3] + (b[:3, 3] - a[:3, 3]) * alpha
    out[:3, :3] = a[:3, :3] @ turn
    return Pose(kin.matrix_to_pose(out))


@_builtin("rotvec2rpy")
def _rotvec2rpy(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    """Roll in (-pi, pi], pitch in [-pi/2, pi/2], yaw in (-pi, pi] (the manual's example: [3.14,
    1.57, 0] gives [-2.80856, -0.16202, 0.9])."""
    r = kin.pose_to_matrix(
        [0, 0, 0, *_three(stmt, arg(stmt, args, kwargs, 0, "rotation_vector"), "rotation_vector")]
    )
    pitch = math.atan2(-r[2, 0], math.hypot(r[0, 0], r[1, 0]))
    if math.hypot(r[0, 0], r[1, 0]) < 1e-12:  # pitch of +-pi/2: roll and yaw turn about one axis
        return [0.0, pitch, math.atan2(-r[0, 1], r[1, 1])]
    return [math.atan2(r[2, 1], r[2, 2]), pitch, math.atan2(r[1, 0], r[0, 0])]


@_builtin("rpy2rotvec")
def _rpy2rotvec(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    roll, pitch, yaw = _three(stmt, arg(stmt, args, kwargs, 0, "rpy_vector"), "rpy_vector")
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return [float(v) for v in kin.matrix_to_rotvec(rz @ ry @ rx)]


@_builtin("size")
def _size(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[int] | int:
    """[rows, columns] of a matrix; the length of an array or a text, as the e-Series Script
    Directory's size(v) gives it (size([1,2,3,4,5]) is 5). PolyScope X's smart skills read the
    rows of a list of directions as `size(dir_list)[0]`."""
    value = arg(stmt, args, kwargs, 0, "v")
    if matrices.is_matrix(value):
        return [len(value), len(value[0])]
    if isinstance(value, (list, str)):
        return len(value)
    raise ScriptFault(
        f"{stmt.name}: needs a matrix, an array or a text, not {type_name(value)}", stmt.line, 1
    )


@_builtin("integer_to_binary_list")
def _integer_to_binary_list(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[bool]:
    """The 32 bits of a signed int, least significant first (the Script Directory's urmath)."""
    x = arg(stmt, args, kwargs, 0, "x")
    if type(x) is not int:
        raise ScriptFault(f"{stmt.name}: x must be an int, not {type_name(x)}", stmt.line, 1)
    return [bool(x >> bit & 1) for bit in range(32)]


@_builtin("binary_list_to_integer")
def _binary_list_to_integer(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    """The signed int of a list of bools, index 0 least significant: 0 for an empty list, the
    first 32 of a longer one (the Script Directory's urmath)."""
    bits = arg(stmt, args, kwargs, 0, "l")
    if not isinstance(bits, list) or not all(isinstance(b, bool) for b in bits):
        raise ScriptFault(f"{stmt.name}: l must be a list of bools", stmt.line, 1)
    value = sum(1 << i for i, b in enumerate(bits[:32]) if b)
    return value - (1 << 32) if value >= 1 << 31 else value


@_builtin("wrench_trans")
def _wrench_trans(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    """A wrench [F, M] given at the frame `T_from_to` places (in its coordinates), seen from the
    frame the pose is given in: F' = R F, M' = R M + p x F' for T = (R, p), the pose_trans way of
    reading a pose. UR's programs that ran on arms fix this way round: the impedance example maps
    a velocity "from offset t to base frame" with wrench_trans(offset_pos, .) (angular and linear
    swapped), its admittance example a flange velocity to the TCP with pose_inv(T_cc_to_tcp), and
    o2ac's inverts the TCP's rotation to get a base force in TCP coordinates."""
    frame = _pose(stmt, arg(stmt, args, kwargs, 0, "T_from_to"))
    wrench = np.array(six(stmt, arg(stmt, args, kwargs, 1, "w_from"), "w_from"))
    rotation, position = frame[:3, :3], frame[:3, 3]
    force = rotation @ wrench[:3]
    moment = rotation @ wrench[3:] + np.cross(position, force)
    return [float(v) for v in (*force, *moment)]
