"""optimovej / optimovel (e-Series 5.21, PolyScope X 10.8): moves whose speed and acceleration are
fractions of the arm's limits, which UR's client library's external control program (the ROS
driver's) uses from those versions on.

`a` and `v` are fractions in (0, 1] of the largest joint (or tool) acceleration and speed; the
controller plans the fastest move within them. The emulator runs an ordinary joint or linear
move at those fractions of its limits: the joint speed of the arm's model (spec/arms), and
acceleration and tool limits that are the emulator's assumption (`OPTIMOVE_*`, in its docs)."""

from __future__ import annotations

import math
from typing import Any

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.motion import JointMove, LinearMove
from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript.calls import Args, Kwargs, WaitFactory, _start, arg, number, six
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.values import Pose

OPTIMOVE_JOINT_A = math.radians(800.0)  # rad/s²: the emulator's largest joint acceleration
OPTIMOVE_JOINT_V = 180.0  # °/s: an arm model that gives no joint speeds
OPTIMOVE_TOOL_V, OPTIMOVE_TOOL_A = 1.0, 5.0  # m/s, m/s²: its largest tool speed and acceleration
OPTIMOVE_A = OPTIMOVE_V = 0.3  # the Script Manual's defaults


def _fraction(stmt: Stmt, value: object, name: str) -> float:
    share = number(stmt, value, name)
    if not 0.0 < share <= 1.0:
        raise ScriptFault(f"{stmt.name}: {name} must be a fraction in (0, 1], not {share:g}", stmt.line, 1)
    return share


def optimove(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    joint = stmt.name == "optimovej"
    target = arg(stmt, args, kwargs, 0, "q" if joint else "pose")
    a = _fraction(stmt, arg(stmt, args, kwargs, 1, "a", OPTIMOVE_A), "a")
    v = _fraction(stmt, arg(stmt, args, kwargs, 2, "v", OPTIMOVE_V), "v")
    r = number(stmt, arg(stmt, args, kwargs, 3, "r", 0.0), "r")
    if joint:
        q: Any = kin.nearest(arm.model, target, arm.state.q, arm.tcp) if isinstance(target, Pose) else None
        q = six(stmt, target, "q") if q is None else q
        speed = math.radians(min(arm.model.joint_speed_deg_s or (OPTIMOVE_JOINT_V,))) * v
        return _start(program, stmt, JointMove(arm.model, arm.state, q, OPTIMOVE_JOINT_A * a, speed, 0.0), r)
    pose = target if isinstance(target, Pose) else kin.forward(arm.model, six(stmt, target, "q"), arm.tcp)
    move = LinearMove(arm.model, arm.tcp, arm.state, pose, OPTIMOVE_TOOL_A * a, OPTIMOVE_TOOL_V * v, 0.0)
    return _start(program, stmt, move, r)


script_calls.COMMANDS.update(optimovej=optimove, optimovel=optimove)
