"""The URScript calls the emulator runs, with the Script manual's arguments and defaults.

COMMANDS act on the robot and may return a wait (the program waits for a motion,
a sleep or a sync); FUNCTIONS return values for expressions. Argument problems are
ScriptFaults at the line, so a program a controller would refuse is refused here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.motion import (
    MOVEJ_A,
    MOVEJ_V,
    MOVEL_A,
    MOVEL_V,
    JointMove,
    JointSpeed,
    LinearMove,
    LinearSpeed,
    Motion,
    Servo,
)
from rtde_spec.emulator.urscript.events import ScriptEvent
from rtde_spec.emulator.urscript.interfaces import Runner, Wait
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.values import (  # noqa: F401 - the calls' value types, re-exported
    INT_MAX,
    INT_MIN,
    MAX_TEXT,
    Pose,
    _is_number,
    arithmetic,
    float_text,
    make_pose,
    type_name,
)

Args = list[Any]
Kwargs = dict[str, Any]
WaitFactory = Callable[[bool], Wait]
CONSTANTS: dict[str, Any] = {"pi": math.pi}
# script function -> (output group, pins it has), names as in the Script manual
DIGITAL = {
    "set_standard_digital_out": ("standard", 8),
    "set_digital_out": ("standard", 8),  # deprecated name of the same
    "set_configurable_digital_out": ("configurable", 8),
    "set_tool_digital_out": ("tool", 2),
}
ANALOG = {"set_standard_analog_out": 2, "set_analog_out": 2}
# set_analog_outputdomain's domain argument, as the Script manual numbers it and RTDE's
# standard_analog_output_type bits (and analog_io_types) encode it
ANALOG_DOMAINS = {0: "current (4-20 mA)", 1: "voltage (0-10 V)"}
MOVES = {"movej", "movel", "movep", "movec", "servoj", "servoc", "speedj", "speedl", "optimovej", "optimovel"}
# the commands a program waits on (direct_torque: builtins_dynamics.py; popup when it blocks)
WAITS = MOVES | {"stopj", "stopl", "sleep", "sync", "halt", "direct_torque", "popup"}


def arg(stmt: Stmt, args: Args, kwargs: Kwargs, index: int, name: str, default: Any = ...) -> Any:
    if index < len(args):
        return args[index]
    if name in kwargs:
        return kwargs[name]
    if default is ...:
        raise ScriptFault(f"{stmt.name}: missing argument {name}", stmt.line, 1)
    return default


def number(stmt: Stmt, value: Any, name: str) -> float:
    if not _is_number(value):
        raise ScriptFault(f"{stmt.name}: {name} must be a number, not {type_name(value)}", stmt.line, 1)
    return float(value)


def six(stmt: Stmt, value: Any, name: str) -> list[float]:
    if not isinstance(value, list) or len(value) != 6 or not all(_is_number(v) for v in value):
        raise ScriptFault(f"{stmt.name}: {name} must be six numbers", stmt.line, 1)
    return [float(v) for v in value]


# --- motion ------------------------------------------------------------------


def _start(program: Runner, stmt: Stmt, motion: Motion, blend: float = 0.0) -> WaitFactory:
    """Run `motion`; the wait ends once it is done (or blends), never before the next control step:
    a move to where the arm already is takes its step too, as on the controller, so a thread that
    repeats one (ur_rtde's servoc thread) yields instead of spinning."""
    arm, thread = program.robot.arm, program.current
    motion.blend, motion.line = max(0.0, blend), stmt.line
    motion.thread_late = lambda: thread.preempted and not thread.done  # Motion.overdue
    arm.move(motion)
    started = program.clock

    def arrived(blend_next: bool) -> bool:
        if program.clock <= started:
            return False
        if arm.motion is not motion or motion.done:
            return True
        return blend_next and motion.blend > 0 and motion.remaining <= motion.blend

    return lambda blend_next: program.wait_for(lambda: arrived(blend_next))


def movej(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    target = arg(stmt, args, kwargs, 0, "q")
    a = number(stmt, arg(stmt, args, kwargs, 1, "a", MOVEJ_A), "a")
    v = number(stmt, arg(stmt, args, kwargs, 2, "v", MOVEJ_V), "v")
    t = number(stmt, arg(stmt, args, kwargs, 3, "t", 0.0), "t")
    r = number(stmt, arg(stmt, args, kwargs, 4, "r", 0.0), "r")
    if isinstance(target, Pose):
        q: Any = kin.nearest(arm.model, target, arm.state.q, arm.tcp)
    else:
        q = six(stmt, target, "q")
    return _start(program, stmt, JointMove(arm.model, arm.state, q, a, v, t), r)


def movel(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    target = arg(stmt, args, kwargs, 0, "pose")
    linear = stmt.name == "movel"
    a = number(stmt, arg(stmt, args, kwargs, 1, "a", MOVEL_A), "a")
    v = number(stmt, arg(stmt, args, kwargs, 2, "v", MOVEL_V), "v")
    t = number(stmt, arg(stmt, args, kwargs, 3, "t", 0.0), "t") if linear else 0.0
    r = number(stmt, arg(stmt, args, kwargs, 4 if linear else 3, "r", 0.0), "r")
    pose = target if isinstance(target, Pose) else kin.forward(arm.model, six(stmt, target, "q"), arm.tcp)
    return _start(program, stmt, LinearMove(arm.model, arm.tcp, arm.state, pose, a, v, t), r)


def speedj(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    qd = six(stmt, arg(stmt, args, kwargs, 0, "qd"), "qd")
    a = number(stmt, arg(stmt, args, kwargs, 1, "a", MOVEJ_A), "a")
    t = number(stmt, arg(stmt, args, kwargs, 2, "t", 0.0), "t")
    return _start(program, stmt, JointSpeed(arm.model, arm.state, qd, a, t))


def speedl(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    xd = six(stmt, arg(stmt, args, kwargs, 0, "xd"), "xd")
    a = number(stmt, arg(stmt, args, kwargs, 1, "a", MOVEL_A), "a")
    t = number(stmt, arg(stmt, args, kwargs, 2, "t", 0.0), "t")
    return _start(program, stmt, LinearSpeed(arm.model, arm.tcp, arm.state, xd, a, t))


def servoj(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    q = six(stmt, arg(stmt, args, kwargs, 0, "q"), "q")
    t = number(stmt, arg(stmt, args, kwargs, 3, "t", 0.002), "t")
    return _start(program, stmt, Servo(arm.state, q, t))


def stopj(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    arm = program.robot.arm
    a = number(stmt, arg(stmt, args, kwargs, 0, "a", MOVEJ_A), "a")
    arm.stop(a, linear=stmt.name == "stopl")
    stopping = arm.motion
    return lambda _: program.wait_for(lambda: stopping is None or arm.motion is not stopping)


def sleep(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    until = program.clock + number(stmt, arg(stmt, args, kwargs, 0, "t"), "t")
    return lambda _: program.wait_for(lambda: program.clock >= until - 1e-9)


def sync(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    start = program.clock
    return lambda _: program.wait_for(lambda: program.clock > start)


# --- I/O and settings ----------------------------------------------------------


def digital_out(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    group, pins = DIGITAL[stmt.name]
    pin, value = arg(stmt, args, kwargs, 0, "n"), arg(stmt, args, kwargs, 1, "b")
    if not isinstance(pin, int) or isinstance(pin, bool) or not 0 <= pin < pins:
        raise ScriptFault(f"{stmt.name}: no output {pin!r} (0 to {pins - 1})", stmt.line, 1)
    if not isinstance(value, bool):
        raise ScriptFault(f"{stmt.name}: b must be a bool, not {type_name(value)}", stmt.line, 1)
    program.robot.apply_inputs(
        {f"{group}_digital_output_mask": 1 << pin, f"{group}_digital_output": int(value) << pin}
    )
    program.applied.append(stmt.text)


def analog_out(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    pin, value = arg(stmt, args, kwargs, 0, "n"), arg(stmt, args, kwargs, 1, "f")
    if not isinstance(pin, int) or isinstance(pin, bool) or not 0 <= pin < ANALOG[stmt.name]:
        raise ScriptFault(f"{stmt.name}: no analog output {pin!r}", stmt.line, 1)
    # a fraction of the output's range, as the RTDE input; the domain (V or mA) stays
    program.robot.values[f"standard_analog_output{pin}"] = min(1.0, max(0.0, number(stmt, value, "f")))
    program.applied.append(stmt.text)


def analog_output_domain(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """set_analog_outputdomain(port, domain): the output's domain, as RTDE's standard_analog_output_type
    sets it for a masked output; its level (the fraction last set) is left as it is."""
    port, domain = arg(stmt, args, kwargs, 0, "port"), arg(stmt, args, kwargs, 1, "domain")
    if (
        not isinstance(port, int)
        or isinstance(port, bool)
        or not 0 <= port < ANALOG["set_standard_analog_out"]
    ):
        raise ScriptFault(f"{stmt.name}: no analog output {port!r}", stmt.line, 1)
    if not isinstance(domain, int) or isinstance(domain, bool) or domain not in ANALOG_DOMAINS:
        known = ", ".join(f"{k} {v}" for k, v in ANALOG_DOMAINS.items())
        raise ScriptFault(f"{stmt.name}: domain must be {known}, not {domain!r}", stmt.line, 1)
    program.robot.apply_inputs(
        {"standard_analog_output_mask": 1 << port, "standard_analog_output_type": domain << port}
    )
    program.applied.append(stmt.text)


def set_tcp(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    pose = arg(stmt, args, kwargs, 0, "pose")
    program.robot.arm.tcp = tuple(six(stmt, pose, "pose"))
    if "tcp_offset" in program.robot.values:
        program.robot.values["tcp_offset"] = program.robot.arm.tcp


def set_payload(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    values = program.robot.values
    if stmt.name != "set_payload_cog":
        mass = number(stmt, arg(stmt, args, kwargs, 0, "m"), "m")
        if mass < 0:
            raise ScriptFault(f"{stmt.name}: a negative mass", stmt.line, 1)
        if "payload" in values:
            values["payload"] = mass
    index = 0 if stmt.name == "set_payload_cog" else 1
    cog = arg(stmt, args, kwargs, index, "CoG", kwargs.get("cog"))
    if cog is not None:
        if not isinstance(cog, list) or len(cog) != 3 or not all(_is_number(v) for v in cog):
            raise ScriptFault(f"{stmt.name}: CoG must be three numbers", stmt.line, 1)
        if "payload_cog" in values:
            values["payload_cog"] = tuple(float(v) for v in cog)


def textmsg(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    text = "".join(to_str(a) for a in (args or [kwargs.get("s1", "")]))
    program.robot.emit(ScriptEvent("text", text, stmt.line, program=program.name))


def popup(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory | None:
    """A popup; a blocking one suspends the program until the operator goes on (the Script manual):
    the program pauses there, as a dashboard `pause` does, and `play` continues it."""
    text = to_str(arg(stmt, args, kwargs, 0, "s"))
    title = to_str(arg(stmt, args, kwargs, 1, "title", "Popup"))
    warning = bool(arg(stmt, args, kwargs, 2, "warning", False))
    error = bool(arg(stmt, args, kwargs, 3, "error", False))
    program.robot.emit(ScriptEvent("popup", text, stmt.line, title=title, warning=warning, error=error))
    pause = getattr(program.robot, "pause_program", None)
    if arg(stmt, args, kwargs, 4, "blocking", False) is not True or pause is None:
        return None
    pause()
    shown = program.clock
    return lambda _: program.wait_for(lambda: program.clock > shown)  # on when played again


def halt(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> WaitFactory:
    def stop(_: bool) -> Wait:
        program.finished = True
        yield

    return stop


Command = Callable[[Runner, Stmt, Args, Kwargs], WaitFactory | None]
COMMANDS: dict[str, Command] = {
    "movej": movej,
    "movel": movel,
    "movep": movel,
    "servoc": movel,  # a blended linear move to the pose, as movep
    "speedj": speedj,
    "speedl": speedl,
    "servoj": servoj,
    "stopj": stopj,
    "stopl": stopj,
    "sleep": sleep,
    "sync": sync,
    **{name: digital_out for name in DIGITAL},
    **{name: analog_out for name in ANALOG},
    "set_analog_outputdomain": analog_output_domain,
    "set_tcp": set_tcp,
    "set_payload": set_payload,
    "set_payload_mass": set_payload,
    "set_payload_cog": set_payload,
    "textmsg": textmsg,
    "popup": popup,
    "halt": halt,
}


# --- functions for expressions -------------------------------------------------


def to_str(value: Any) -> str:
    """The text URScript shows for a value; a list nested past 64 levels or a text past MAX_TEXT
    is a ValueError (a runtime exception of the statement), not a recursion or memory fault."""
    parts: list[str] = []
    _text_of(value, parts, [MAX_TEXT], 0)
    return "".join(parts)


def _text_of(value: Any, parts: list[str], left: list[int], depth: int) -> None:
    if depth > 64:
        raise ValueError("to_str: a list nested more than 64 levels")
    if isinstance(value, Pose):  # before list: a pose is a list too, but shows as p[...]
        parts.append("p[" + ", ".join(float_text(float(v)) for v in value) + "]")
    elif isinstance(value, list):
        parts.append("[")
        for i, item in enumerate(value):
            if i:
                parts.append(", ")
            _text_of(item, parts, left, depth + 1)
        parts.append("]")
    elif isinstance(value, float):
        parts.append(float_text(value))
    elif isinstance(value, (int, str)):  # a bool too: True, False
        parts.append(str(value))
    else:  # "Any other type will raise an exception" (the Script Directory's str_cat, to_str)
        raise ValueError(f"a {type_name(value)} has no text (only bools, numbers, texts, poses and lists)")
    left[0] -= len(parts[-1]) + 2
    if left[0] < 0:
        raise ValueError(f"to_str: text over {MAX_TEXT} characters")


def _pose_op(fn: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> Callable[[Any, Any], Pose]:
    def apply(p1: Any, p2: Any) -> Pose:
        return Pose(kin.matrix_to_pose(fn(kin.pose_to_matrix(p1), kin.pose_to_matrix(p2))))

    return apply


def call_function(program: Runner, stmt: Stmt, name: str, args: Args, kwargs: Kwargs) -> Any:
    arm = program.robot.arm
    values = program.robot.values

    def _tcp(index: int) -> Any:
        """The `tcp` argument (get_forward_kin's 2nd, get_inverse_kin's 5th), else the active TCP."""
        tcp = arg(stmt, args, kwargs, index, "tcp", None)
        return arm.tcp if tcp is None else six(stmt, tcp, "tcp")

    table: dict[str, Callable[[], Any]] = {
        "d2r": lambda: math.radians(args[0]),
        "r2d": lambda: math.degrees(args[0]),
        "sqrt": lambda: math.sqrt(args[0]),
        "sin": lambda: math.sin(args[0]),
        "cos": lambda: math.cos(args[0]),
        "tan": lambda: math.tan(args[0]),
        "atan2": lambda: math.atan2(args[0], args[1]),
        "norm": lambda: float(np.linalg.norm(args[0])),
        "to_str": lambda: to_str(args[0]),
        "str_cat": lambda: to_str(args[0]) + to_str(args[1]),
        "get_actual_joint_positions": lambda: [float(v) for v in arm.state.q],
        "get_target_joint_positions": lambda: [float(v) for v in arm.state.q],
        "get_actual_tcp_pose": lambda: Pose(arm.pose()),
        "get_target_tcp_pose": lambda: Pose(arm.pose()),
        "get_forward_kin": lambda: Pose(
            kin.forward(arm.model, six(stmt, arg(stmt, args, kwargs, 0, "q", [*arm.state.q]), "q"), _tcp(1))
        ),
        "get_inverse_kin": lambda: list(
            kin.nearest(arm.model, args[0], arg(stmt, args, kwargs, 1, "qnear", list(arm.state.q)), _tcp(4))
        ),
        "pose_trans": lambda: _pose_op(lambda a, b: a @ b)(args[0], args[1]),
        "pose_inv": lambda: Pose(
            kin.matrix_to_pose(np.linalg.inv(kin.pose_to_matrix(args[0])).astype(np.float64))
        ),
        "pose_add": lambda: Pose(
            kin.matrix_to_pose(_pose_add(kin.pose_to_matrix(args[0]), kin.pose_to_matrix(args[1])))
        ),
        "get_speed_slider_fraction": lambda: float(values.get("target_speed_fraction", 1.0)),
    }
    fn = table.get(name)
    if fn is None:
        raise ScriptFault.name_not_found(name, stmt.line, 1)
    try:
        return fn()
    except (IndexError, TypeError, ValueError, ArithmeticError) as exc:
        raise ScriptFault(f"{name}: bad arguments ({exc})", stmt.line, 1) from exc


def _pose_add(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, 3] = a[:3, 3] + b[:3, 3]
    out[:3, :3] = b[:3, :3] @ a[:3, :3]
    return out


FUNCTIONS = {
    "d2r", "r2d", "sqrt", "sin", "cos", "tan", "atan2", "norm", "to_str", "str_cat",
    "get_actual_joint_positions", "get_target_joint_positions", "get_actual_tcp_pose", "get_target_tcp_pose",
    "get_forward_kin", "get_inverse_kin", "pose_trans", "pose_inv", "pose_add", "get_speed_slider_fraction",
}  # fmt: skip
