"""The built-ins of the arm's model (e-Series 5.23 on) and the matrix functions beside them.

get_jacobian and its time derivative are the arm's own (arm/jacobian.py, from the DH rows);
get_mass_matrix and get_coriolis_and_centrifugal_torques are arm/dynamics.py's simple model (the
emulator knows no link masses: docs/decisions.md), with the payload the program set;
get_target_joint_accelerations is the motion's (zero when still). Matrices come back as URScript
matrices (lists of rows), so `m[i, j]` reads them as on a controller.

direct_torque takes its control step, as on a robot (a torque loop calls it once a step without a
sync), and shows control mode TORQUE while it is called; with no dynamics to integrate, the arm
holds where it is, as UR's own simulator does (torque commands have no effect there).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rtde_spec.emulator.arm import dynamics
from rtde_spec.emulator.arm import jacobian as jac
from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript import matrices
from rtde_spec.emulator.urscript.builtins_modes import settings_of
from rtde_spec.emulator.urscript.calls import WaitFactory, arg, number, six
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar
from rtde_spec.emulator.urscript.values import Pose, type_name

Args = list[Any]
Kwargs = dict[str, Any]
Builtin = Callable[[Runner, Stmt, Args, Kwargs], Any]
DYNAMICS: dict[str, Builtin] = {}
VISCOUS_SCALE = (0.9, 0.9, 0.8, 0.9, 0.9, 0.9)  # direct_torque's defaults (Script Manual 5.25.1)
COULOMB_SCALE = (0.8, 0.8, 0.7, 0.8, 0.8, 0.8)


_builtin = registrar(DYNAMICS)


def _rows(matrix: np.ndarray) -> list[list[float]]:
    return [[float(v) for v in row] for row in matrix]


def _joints(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs, index: int, name: str) -> list[float]:
    """A joint vector argument (q, qd), or the arm's own when left out."""
    state = runner.robot.arm.state
    value = arg(stmt, args, kwargs, index, name, None)
    if value is None:
        return [float(v) for v in (state.q if name == "q" else state.qd)]
    return six(stmt, value, name)


def _tcp(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs, index: int) -> list[float]:
    value = arg(stmt, args, kwargs, index, "tcp", None)
    return [float(v) for v in runner.robot.arm.tcp] if value is None else six(stmt, value, "tcp")


def _payload(runner: Runner) -> tuple[float, Any, Any]:
    """The active payload: mass, centre of gravity, inertia (set_target_payload's)."""
    values = runner.robot.values
    return (
        float(values.get("payload", 0.0)),
        values.get("payload_cog", (0.0, 0.0, 0.0)),
        values.get("payload_inertia", None),
    )


@_builtin("get_jacobian")
def _jacobian(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[list[float]]:
    model = runner.robot.arm.model
    q, tcp = _joints(runner, stmt, args, kwargs, 0, "q"), _tcp(runner, stmt, args, kwargs, 1)
    return _rows(jac.jacobian(model, q, tcp))


@_builtin("get_jacobian_time_derivative")
def _jacobian_derivative(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[list[float]]:
    q, qd = _joints(runner, stmt, args, kwargs, 0, "q"), _joints(runner, stmt, args, kwargs, 1, "qd")
    tcp = _tcp(runner, stmt, args, kwargs, 2)
    return _rows(jac.jacobian_derivative(runner.robot.arm.model, q, qd, tcp))


@_builtin("get_mass_matrix")
def _mass_matrix(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[list[float]]:
    q = _joints(runner, stmt, args, kwargs, 0, "q")
    rotors = arg(stmt, args, kwargs, 1, "include_rotors_inertia", False)
    if not isinstance(rotors, bool):
        raise ScriptFault(f"{stmt.name}: include_rotors_inertia must be a bool", stmt.line, stmt.column or 1)
    mass, cog, inertia = _payload(runner)
    return _rows(dynamics.mass_matrix(runner.robot.arm.model, q, mass, cog, inertia, rotors))


@_builtin("get_coriolis_and_centrifugal_torques")
def _coriolis(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    q, qd = _joints(runner, stmt, args, kwargs, 0, "q"), _joints(runner, stmt, args, kwargs, 1, "qd")
    mass, cog, inertia = _payload(runner)
    return [float(v) for v in dynamics.coriolis_torques(runner.robot.arm.model, q, qd, mass, cog, inertia)]


@_builtin("get_target_joint_accelerations")
def _target_accelerations(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    return [float(v) for v in runner.robot.arm.state.qdd]


@_builtin("transpose")
def _transpose(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[Any]:
    return matrices.transpose(arg(stmt, args, kwargs, 0, "m"), stmt.line, stmt.column or 1)


@_builtin("inv")
def _inv(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    value = arg(stmt, args, kwargs, 0, "m")
    if isinstance(value, Pose):  # the inverse transformation, as pose_inv
        return Pose(kin.matrix_to_pose(np.linalg.inv(kin.pose_to_matrix(value)).astype(np.float64)))
    return matrices.inverse(value, stmt.line, stmt.column or 1)


def _scales(stmt: Stmt, value: Any, name: str) -> list[float]:
    scales = six(stmt, value, name)
    if not all(0.0 <= v <= 1.0 for v in scales):
        raise ScriptFault(f"{stmt.name}: {name} must be between 0 and 1", stmt.line, stmt.column or 1)
    return scales


def direct_torque(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    """Target joint torques for this control step (after gravity compensation); the arm holds."""
    torque = arg(stmt, args, kwargs, 0, "torque")
    if not isinstance(torque, list) or len(torque) != 6:
        raise ScriptFault(f"{stmt.name}: torque must be six numbers", stmt.line, stmt.column or 1)
    torque = [number(stmt, v, "torque") for v in torque]
    legacy = len(args) > 1 and isinstance(args[1], bool)  # 5.23's direct_torque(torque, friction_comp)
    friction = args[1] if legacy else kwargs.get("friction_comp", True)
    if not isinstance(friction, bool):
        raise ScriptFault(
            f"{stmt.name}: friction_comp must be a bool, not {type_name(friction)}",
            stmt.line,
            stmt.column or 1,
        )
    rest = args[2:] if legacy else args[1:]
    viscous = _scales(
        stmt, rest[0] if rest else kwargs.get("viscous_scale", list(VISCOUS_SCALE)), "viscous_scale"
    )
    coulomb = _scales(
        stmt, rest[1] if len(rest) > 1 else kwargs.get("coulomb_scale", list(COULOMB_SCALE)), "coulomb_scale"
    )
    arm = program.robot.arm
    if arm.motion is not None:
        arm.halt()  # torque control takes the arm from any motion; nothing moves it here
    start = program.clock
    settings_of(program)["_direct_torque"] = (start, torque, viscous, coulomb, friction)
    return lambda _: program.wait_for(lambda: program.clock > start)


script_calls.COMMANDS["direct_torque"] = direct_torque
