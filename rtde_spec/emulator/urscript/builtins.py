"""The built-in functions a program calls for a value or an effect, beyond script_calls' motions
and I/O: the RTDE registers (bound to the RTDE server's input and output registers), the
kinematics queries, the sockets (sockets.py), the modes and settings (builtins_modes.py), the
arm's model and matrices (builtins_dynamics.py), the pose maths (builtins_poses.py) and the world
model's frames (world_model.py) (docs/reference/urscript.md lists each function
with its source in UR's Script Manual).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import cache
from typing import Any

import numpy as np

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.motion import JointMove, LinearMove
from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript import (
    eip,
    optimove,  # noqa: F401 - registers optimovej/optimovel
    rpc,
    sockets,
)
from rtde_spec.emulator.urscript.builtins_dynamics import DYNAMICS
from rtde_spec.emulator.urscript.builtins_io import IO
from rtde_spec.emulator.urscript.builtins_modes import MODES, settings_of
from rtde_spec.emulator.urscript.builtins_poses import POSES
from rtde_spec.emulator.urscript.builtins_readings import READINGS
from rtde_spec.emulator.urscript.builtins_text import TEXT
from rtde_spec.emulator.urscript.builtins_values import VALUES
from rtde_spec.emulator.urscript.calls import Pose, number, six, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.interpreter_mode import IMODE, waiting
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar
from rtde_spec.emulator.urscript.world_model import WORLD
from rtde_spec.errors import RtdeSpecError

Args = list[Any]
Kwargs = dict[str, Any]
Builtin = Callable[[Runner, Stmt, Args, Kwargs], Any]
BUILTINS: dict[str, Builtin] = {}
WAITING: dict[str, Callable[[Runner, Stmt, Args, Kwargs], sockets.Waiting]] = dict(sockets.READERS)
WAITING.update(socket_open=sockets.socket_open, socket_get_var=sockets.socket_get_var)
WAITING.update(socket_read_string=sockets.socket_read_string, interpreter_mode=waiting)

builtin = registrar(BUILTINS)


def names() -> set[str]:
    """Every name a program may call without defining it."""
    return set(BUILTINS) | set(WAITING) | set(script_calls.COMMANDS) | set(script_calls.FUNCTIONS)


@cache
def names_for(line: str, version: str, inherits: str | None = None) -> frozenset[str]:
    """The built-ins a controller of this product line and version has (spec/urscript's `since`).
    A function the line's `since` does not name is the line's from its first release when it names
    the line this one `inherits` (PolyScope X grew out of the e-Series software,
    spec/common/product_lines.yaml); a line the table does not cover gets every one the emulator runs."""
    from rtde_spec.metamodel.urscript import urscript_functions
    from rtde_spec.metamodel.versions import Version

    table = urscript_functions()
    if line not in table.product_lines:
        return frozenset(names())
    have = Version.parse(version)
    return frozenset(
        f.name
        for f in table.functions
        if (Version.parse(f.since[line]) <= have if line in f.since else inherits in f.since)
    )


def call(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    fn = BUILTINS.get(stmt.name)
    if fn is None:
        return script_calls.call_function(runner, stmt, stmt.name, args, kwargs)
    try:
        return fn(runner, stmt, args, kwargs)
    except ScriptFault:
        raise
    except (IndexError, TypeError, ValueError, ArithmeticError, KeyError) as exc:
        raise ScriptFault(f"{stmt.name}: bad arguments ({exc})", stmt.line, stmt.column or 1) from exc


def field(value: Any, name: str, line: int, column: int) -> Any:
    """`s.name` of a struct."""
    if not isinstance(value, dict) or name not in value:
        raise ScriptFault(f"Type error: {type_name(value)} has no field {name}", line, column)
    return value[name]


def _arg(stmt: Stmt, args: Args, kwargs: Kwargs, index: int, name: str, default: Any = ...) -> Any:
    return script_calls.arg(stmt, args, kwargs, index, name, default)


# the RTDE field families the register functions read and write (their addresses: the spec's)
_FAMILIES = {"integer": "int", "float": "double", "boolean": "bit"}


@cache
def _addresses(family: str) -> tuple[int, int]:
    """(first, last) index of the RTDE output fields `output_<family>_register_{X}` (spec/rtde)."""
    from rtde_spec.metamodel.catalogue import Catalogue

    name = f"output_{family}_register_{{X}}"
    found = [f.index for f in Catalogue.builtin().fields() if f.family == name and f.index is not None]
    return min(found), max(found)


def _last_register(kind: str) -> int:
    """Integers and floats: RTDE's 0 to 47; booleans: up to RTDE's last single bit field (127)."""
    return _addresses(_FAMILIES[kind])[1]


def _bit_words() -> int:
    """Boolean registers below this are bits of RTDE's two 32-bit words; from it, BOOL fields."""
    return _addresses("bit")[0]


def _register(stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    n = _arg(stmt, args, kwargs, 0, "address")
    last = _last_register(stmt.name.split("_")[2])
    if not isinstance(n, int) or isinstance(n, bool) or not 0 <= n <= last:
        raise ScriptFault(f"{stmt.name}: no register {n!r} (0 to {last})", stmt.line, stmt.column or 1)
    return n


def _bit(values: Mapping[str, Any], direction: str, n: int) -> bool:
    """Boolean register `n` as RTDE carries it: a bit of a 32-bit word, or a BOOL field of its own."""
    if n >= _bit_words():
        return bool(values.get(f"{direction}_bit_register_{n}", False))
    word = values.get(
        f"{direction}_bit_registers0_to_31" if n < 32 else f"{direction}_bit_registers32_to_63", 0
    )
    return bool(int(word) >> (n % 32) & 1)


# --- RTDE registers: the same values the RTDE server reads and writes ----------------------------


@builtin("read_input_integer_register", "read_input_float_register", "read_input_boolean_register")
def _read_input(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    kind = stmt.name.split("_")[2]
    n = _register(stmt, args, kwargs)
    rtde = {"integer": "int", "float": "double", "boolean": "bit"}[kind]
    if kind == "boolean":
        return _bit(runner.robot.values, "input", n)
    value = runner.robot.values.get(f"input_{rtde}_register_{n}", 0)
    return float(value) if kind == "float" else int(value)


@builtin("read_output_integer_register", "read_output_float_register", "read_output_boolean_register")
def _read_output(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    """What the program (or an earlier one) wrote to an output register, as RTDE clients read it."""
    kind = stmt.name.split("_")[2]
    n = _register(stmt, args, kwargs)
    values = runner.robot.values
    if kind == "boolean":
        return _bit(values, "output", n)
    value = values.get(f"output_{'int' if kind == 'integer' else 'double'}_register_{n}", 0)
    return float(value) if kind == "float" else int(value)


@builtin("write_output_integer_register", "write_output_float_register", "write_output_boolean_register")
def _write_output(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    kind = stmt.name.split("_")[2]
    n = _register(stmt, args, kwargs)
    value = _arg(stmt, args, kwargs, 1, "value")
    values = runner.robot.values
    if kind == "boolean" and n >= _bit_words():
        values[f"output_bit_register_{n}"] = bool(value)
        return
    if kind == "boolean":
        key = "output_bit_registers0_to_31" if n < 32 else "output_bit_registers32_to_63"
        bit = 1 << (n % 32)
        values[key] = (int(values.get(key, 0)) | bit) if bool(value) else (int(values.get(key, 0)) & ~bit)
        return
    if kind == "integer":
        if not isinstance(value, int) or isinstance(value, bool):
            raise ScriptFault(f"{stmt.name}: value must be an int, not {type_name(value)}", stmt.line, 1)
        values[f"output_int_register_{n}"] = value
    else:
        values[f"output_double_register_{n}"] = number(stmt, value, "value")


@builtin("rtde_set_watchdog")
def _watchdog(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    name = _arg(stmt, args, kwargs, 0, "variable_name")
    hz = number(stmt, _arg(stmt, args, kwargs, 1, "min_frequency"), "min_frequency")
    action = _arg(stmt, args, kwargs, 2, "action", "pause")
    action = action.lower() if isinstance(action, str) else action  # UR's own example says "PAUSE"
    if not isinstance(name, str) or action not in ("ignore", "pause", "stop"):
        raise ScriptFault(f"{stmt.name}: needs an input name and ignore, pause or stop", stmt.line, 1)
    if hz <= 0:
        raise ScriptFault(f"{stmt.name}: min_frequency must be above 0", stmt.line, 1)
    settings_of(runner).setdefault("watchdogs", {})[name] = (
        hz,
        action,
        float(getattr(runner.robot, "time", 0.0)),
    )


@builtin("get_steptime")
def _steptime(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    return 1.0 / float(getattr(runner.robot, "base_hz", 500))


# --- motions the emulator approximates ---------------------------------------------------------


def movec(program: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> script_calls.WaitFactory:
    """movec: approximated as a linear move to pose_to (the arc through pose_via is not modelled)."""
    arm = program.robot.arm
    target = _arg(stmt, args, kwargs, 1, "pose_to")
    a = number(stmt, _arg(stmt, args, kwargs, 2, "a", script_calls.MOVEL_A), "a")
    v = number(stmt, _arg(stmt, args, kwargs, 3, "v", script_calls.MOVEL_V), "v")
    r = number(stmt, _arg(stmt, args, kwargs, 4, "r", 0.0), "r")
    pose = target if isinstance(target, Pose) else kin.forward(arm.model, six(stmt, target, "q"), arm.tcp)
    return script_calls._start(
        program, stmt, script_calls.LinearMove(arm.model, arm.tcp, arm.state, pose, a, v, 0.0), r
    )


script_calls.COMMANDS["movec"] = movec


# --- the arm's state, settings and modes --------------------------------------------------------


def _values(name: str, default: Any) -> Builtin:
    def read(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
        where = settings_of(runner) if name.startswith("_") else runner.robot.values
        value = where.get(name, default)
        return [float(v) for v in value] if isinstance(value, (tuple, list)) else value

    return read


BUILTINS["get_target_tcp_speed"] = _values("target_TCP_speed", (0.0,) * 6)
BUILTINS["get_actual_tcp_speed"] = _values("actual_TCP_speed", (0.0,) * 6)
BUILTINS["get_joint_torques"] = _values("_joint_torques", (0.0,) * 6)
BUILTINS["get_target_payload"] = _values("payload", 0.0)
BUILTINS["get_target_payload_cog"] = _values("payload_cog", (0.0,) * 3)
BUILTINS["get_target_payload_inertia"] = _values("payload_inertia", (0.0,) * 6)
# the Script Manual's 0 (normal operation; 1, 2: near a singularity, which is not modelled)
BUILTINS["get_freedrive_status"] = lambda runner, stmt, args, kwargs: 0
BUILTINS["get_actual_joint_speeds"] = _values("actual_qd", (0.0,) * 6)
BUILTINS["get_target_joint_speeds"] = _values("target_qd", (0.0,) * 6)
BUILTINS["get_tcp_force"] = _values("actual_TCP_force", (0.0,) * 6)


@builtin("get_tcp_offset")
def _tcp(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    return Pose(float(v) for v in runner.robot.arm.tcp)


@builtin("get_actual_tool_flange_pose")
def _flange(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    arm = runner.robot.arm
    return Pose(kin.forward(arm.model, list(arm.state.q)))


@builtin("get_actual_joint_positions_history")
def _history(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    arm = runner.robot.arm  # the emulator keeps no history: the present position
    return [float(v) for v in arm.state.q]


@builtin("get_target_waypoint")
def _waypoint(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    """Where the active movej/movel/movep goes (a relative move after a blend starts from it), not
    the pose of this step; with no such move, the target TCP pose."""
    arm = runner.robot.arm
    motion = arm.motion
    if isinstance(motion, LinearMove):
        return Pose(motion.pose_at(motion.length))
    if isinstance(motion, JointMove):
        return Pose(kin.forward(arm.model, motion.start.q + motion.delta, arm.tcp))
    return Pose(arm.pose())


_TABLES = (sockets.SENDERS, MODES, DYNAMICS, IO, POSES, TEXT, VALUES, WORLD, READINGS, eip.FACTORIES, IMODE)
for _table in _TABLES:
    BUILTINS.update(_table)
BUILTINS["socket_close"] = sockets.socket_close
BUILTINS["socket_set_var"] = sockets.socket_set_var
BUILTINS["rpc_factory"] = rpc.rpc_factory
BUILTINS["get_joint_positions"] = lambda runner, stmt, args, kwargs: [
    float(v) for v in runner.robot.arm.state.q
]


@builtin("is_steady")
def _steady(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
    arm = runner.robot.arm
    return arm.motion is None and not np.any(arm.state.qd)


@builtin("get_inverse_kin_has_solution", "is_within_safety_limits")
def _reachable(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
    arm, limits = runner.robot.arm, stmt.name == "is_within_safety_limits"
    target = _arg(stmt, args, kwargs, 0, "position" if limits else "pose")  # the manual's names
    if limits and not isinstance(target, Pose):
        q = six(stmt, target, "q")
        return all(low <= v <= high for v, (low, high) in zip(q, arm.model.joint_limits, strict=True))
    tcp = None if limits else _arg(stmt, args, kwargs, 4, "tcp", None)
    tcp = arm.tcp if tcp is None else six(stmt, tcp, "tcp")
    try:
        kin.nearest(arm.model, six(stmt, target, "pose"), arm.state.q, tcp)
    except (ArithmeticError, ValueError, RtdeSpecError):  # no solution is the answer
        return False
    return True


@builtin("tool_contact")
def _contact(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    return 0  # the emulated arm meets nothing


# --- numbers, lists and texts -----------------------------------------------------------------


def _math(fn: Callable[..., Any], count: int) -> Builtin:
    def apply(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
        return fn(*(number(stmt, a, "x") for a in args[:count]))

    return apply


for _name, _fn, _count in (
    ("pow", math.pow, 2), ("acos", math.acos, 1), ("asin", math.asin, 1), ("atan", math.atan, 1),
    ("log", lambda b, f: math.log(f, b), 2), ("floor", math.floor, 1), ("ceil", math.ceil, 1),
):  # fmt: skip
    BUILTINS[_name] = _math(_fn, _count)


@builtin("length")
def _length_of(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    value = _arg(stmt, args, kwargs, 0, "v")
    if isinstance(value, str):
        return len(value)
    if not isinstance(value, list):
        raise ScriptFault(f"{stmt.name}: not a list or a text but {type_name(value)}", stmt.line, 1)
    return len(value)


@builtin("get_list_length")
def _length(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    value = args[0]
    if not isinstance(value, list):
        raise ScriptFault(f"{stmt.name}: not a list", stmt.line, 1)
    return len(value)


@builtin("str_len")
def _str_len(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    return len(script_calls.to_str(args[0]))


@builtin("to_num")
def _to_num(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Any:
    text = str(args[0]).strip()
    hexa = text.lstrip("+-")[:2].lower() == "0x"  # no '.': an int, "0x3A" too (the Script Directory)
    try:
        value = int(text, 16 if hexa else 10) if text.lstrip("+-").isdigit() or hexa else float(text)
        if type(value) is int and not script_calls.INT_MIN <= value <= script_calls.INT_MAX:
            raise ValueError
        return value
    except ValueError:
        raise ScriptFault(f"to_num: not a number of its type: {text[:40]!r}", stmt.line, 1) from None


@builtin("struct")
def _struct(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> dict[str, Any]:
    return dict(kwargs)


@builtin("is_nan")
def _is_nan(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
    return math.isnan(number(stmt, args[0], "x"))


@builtin("normalize")
def _normalize(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> list[float]:
    values = [number(stmt, v, "x") for v in args[0]]
    size = math.sqrt(sum(v * v for v in values))
    return [v / size for v in values] if size else values


@builtin("norm")
def _norm(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> float:
    value = args[0]
    if isinstance(value, list):
        return math.sqrt(sum(number(stmt, v, "a") ** 2 for v in value))
    return abs(number(stmt, value, "a"))
