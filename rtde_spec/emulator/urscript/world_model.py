"""URScript's world model: named coordinate frames in a tree, as PolyScope X programs use them.

"world" is the root and never moves. "base" starts at the world origin and may be moved or
attached elsewhere (a robot on a rail). "flange" hangs from the base where the arm's joints put it,
"tcp" from the flange by the active TCP offset (set_tcp), so both follow every step of a motion. A
program adds frames of its own; a frame attached to the tcp moves with the tool. A frame's pose is
its parent's composed with its offset, as rigid transforms (a rotation and a translation, the
maths of pose_trans and pose_inv), in plain Python: a chain of frames costs no BLAS call, whose
kernels raise spurious overflow flags on 4x4 products on some machines.

The functions and their rules are those of UR's World Model API (MotionPlus documentation, "World
Model API: URScript Functions"): add_frame puts a frame in the world without attaching it;
attach_frame keeps the child where it is in the world; world, flange and tcp are never attached
elsewhere, and no attachment may close a chain; delete_frame and delete_all_frames hang what was
attached to a deleted frame on "world" where it stands; the robot's four frames are never deleted.

Why the model lives with the controller, not with the program: the same documentation ("World
Model: Persistence") says changes to it persist between program runs and reset_world_model()
clears the user-defined frames and puts the base back at the world origin; PolyScope X's
application script calls it first, then builds its frames. The robot object holds it (`world_of`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.state import Arm
from rtde_spec.emulator.urscript.calls import Pose, arg, six, type_name
from rtde_spec.emulator.urscript.interfaces import Robot, Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
Builtin = Callable[[Runner, Stmt, Args, Kwargs], Any]
Transform = tuple[kin.Rot, kin.Vec3]  # a rotation, then a translation: p -> R p + t
IDENTITY: Transform = (kin.rotvec_to_rot((0.0, 0.0, 0.0)), (0.0, 0.0, 0.0))
WORLD: dict[str, Builtin] = {}

ROBOT_FRAMES = ("world", "base", "flange", "tcp")
PINNED = frozenset({"world", "flange", "tcp"})  # the root and the arm's own: never attached nor moved
MAX_FRAMES = 1024  # frames a program may add: the model outlives programs, so it must not grow unbounded
MAX_DEPTH = 64  # frames between one and the world: a pose is asked of the chain within a statement
SHOWN = 8  # frame names an error lists


class FrameError(Exception):
    """A request the world model refuses; the text of the program's runtime exception."""


@dataclass
class _Frame:
    parent: str
    offset: Transform  # the frame in its parent's coordinates


def compose(a: Transform, b: Transform) -> Transform:
    """`b` given in `a`'s coordinates, in the coordinates `a` is given in (pose_trans)."""
    moved = kin.apply(a[0], b[1])
    return kin.mul(a[0], b[0]), (moved[0] + a[1][0], moved[1] + a[1][1], moved[2] + a[1][2])


def inverse(a: Transform) -> Transform:
    """The inverse of a rigid transform, exactly (the rotation's transpose)."""
    back = kin.transpose(a[0])
    moved = kin.apply(back, a[1])
    return back, (-moved[0], -moved[1], -moved[2])


def from_pose(pose: kin.Floats) -> Transform:
    return kin.rotvec_to_rot(pose[3:6]), (float(pose[0]), float(pose[1]), float(pose[2]))


def to_pose(a: Transform) -> Pose:
    return Pose([*a[1], *kin.matrix_to_rotvec(a[0])])


class WorldModel:
    """The frames of one controller: the robot's four and those programs added (`frames` holds
    "base" and the added ones; flange and tcp are read from the arm when asked)."""

    def __init__(self) -> None:
        self.frames: dict[str, _Frame] = {}
        self.reset()

    def reset(self) -> None:
        """reset_world_model(): no frames but the robot's, the base at the world origin."""
        self.frames = {"base": _Frame("world", IDENTITY)}

    # --- reading -------------------------------------------------------------------------------

    def has(self, name: str) -> bool:
        return name in ROBOT_FRAMES or name in self.frames

    def names(self) -> list[str]:
        return [*ROBOT_FRAMES, *(n for n in self.frames if n != "base")]

    def _known(self, name: str) -> None:
        if not self.has(name):
            shown = ", ".join(self.names()[:SHOWN]) + (", ..." if len(self.names()) > SHOWN else "")
            raise FrameError(f"no frame named {name!r} in the world model (it has {shown})")

    def _link(self, name: str, arm: Arm) -> tuple[str, Transform]:
        """A frame's parent and its offset there; flange and tcp as the arm has them now."""
        if name == "flange":
            return "base", kin.flange_frame(arm.model, arm.state.q)
        if name == "tcp":
            return "flange", from_pose(arm.tcp)
        frame = self.frames[name]
        return frame.parent, frame.offset

    def parent(self, name: str) -> str:
        self._known(name)
        if name == "world":
            raise FrameError("'world' is the root of the world model: it has no parent")
        return {"flange": "base", "tcp": "flange"}.get(name) or self.frames[name].parent

    def _ancestors(self, name: str) -> list[str]:
        chain = []
        while name != "world":
            name = self.parent(name)
            chain.append(name)
        return chain

    def _height(self, name: str) -> int:
        """How many frames hang in a line from `name`, itself included."""
        below: dict[str, list[str]] = {}
        for child, frame in self.frames.items():
            below.setdefault(frame.parent, []).append(child)
        below.setdefault("base", []).append("flange")  # the arm's own frames
        below.setdefault("flange", []).append("tcp")
        height, level = 0, [name]
        while level:
            height += 1
            level = [child for frame in level for child in below.get(frame, [])]
        return height

    def in_world(self, name: str, arm: Arm) -> Transform:
        """The frame in world coordinates: its offsets composed up to the root."""
        self._known(name)
        out = IDENTITY
        while name != "world":
            name, offset = self._link(name, arm)
            out = compose(offset, out)
        return out

    def pose(self, name: str, ref: str, arm: Arm) -> Transform:
        """get_pose: frame `name` in `ref`'s coordinates."""
        return compose(inverse(self.in_world(ref, arm)), self.in_world(name, arm))

    def convert(self, pose: Transform, source: str, target: str, arm: Arm) -> Transform:
        """convert_pose: a pose given in `source`'s coordinates, in `target`'s."""
        return compose(self.pose(source, target, arm), pose)

    # --- changing ------------------------------------------------------------------------------

    def add(self, name: str, pose: Transform, ref: str, arm: Arm) -> None:
        """add_frame: a new frame at `pose` in `ref`, attached to "world" (not to `ref`)."""
        if self.has(name):
            robot = " (world, base, flange and tcp are the robot's)" if name in ROBOT_FRAMES else ""
            raise FrameError(f"a frame named {name!r} exists already{robot}")
        if len(self.frames) - 1 >= MAX_FRAMES:  # "base" is the robot's
            raise FrameError(f"the world model holds at most {MAX_FRAMES} frames of programs")
        self.frames[name] = _Frame("world", compose(self.in_world(ref, arm), pose))

    def attach(self, child: str, parent: str, arm: Arm) -> None:
        """attach_frame: `child` hangs from `parent` from now on, where it is in the world."""
        self._known(child)
        self._known(parent)
        if child in PINNED:
            raise FrameError(
                f"{child!r} cannot be attached elsewhere (world, flange and tcp stay as they are)"
            )
        if child == parent:
            raise FrameError(f"{child!r} cannot be attached to itself")
        chain = [parent, *self._ancestors(parent)]
        if child in chain:
            path = " -> ".join(chain[: chain.index(child) + 1])
            raise FrameError(f"attaching {child!r} to {parent!r} would close a chain ({path} already)")
        depth = len(chain) + self._height(child)
        if depth > MAX_DEPTH:
            raise FrameError(
                f"attaching {child!r} to {parent!r} would chain {depth} frames (at most {MAX_DEPTH})"
            )
        placed = self.in_world(child, arm)
        self.frames[child] = _Frame(parent, compose(inverse(self.in_world(parent, arm)), placed))

    def move(self, name: str, pose: Transform, ref: str, arm: Arm) -> None:
        """move_frame: `name` to `pose` in `ref` (as `ref` is now), still attached to its parent."""
        self._known(name)
        if name in PINNED:
            raise FrameError(f"{name!r} cannot be moved (world is fixed, flange and tcp follow the arm)")
        target = compose(self.in_world(ref, arm), pose)
        frame = self.frames[name]
        frame.offset = compose(inverse(self.in_world(frame.parent, arm)), target)

    def delete(self, name: str, arm: Arm) -> None:
        self._known(name)
        if name in ROBOT_FRAMES:
            raise FrameError(
                f"{name!r} is one of the robot's frames (world, base, flange, tcp): never deleted"
            )
        self._remove({name}, arm)

    def delete_all(self, arm: Arm) -> None:
        self._remove({n for n in self.frames if n != "base"}, arm)

    def _remove(self, names: set[str], arm: Arm) -> None:
        """Drop `names`; what hung from them hangs from "world" where it stands."""
        orphans = {
            n: self.in_world(n, arm)
            for n, frame in self.frames.items()
            if n not in names and frame.parent in names
        }
        for name in names:
            del self.frames[name]
        for name, placed in orphans.items():
            self.frames[name] = _Frame("world", placed)


def world_of(robot: Robot) -> WorldModel:
    """The controller's world model, made the first time a program asks for it."""
    model = getattr(robot, "world_model", None)
    if model is None:
        model = WorldModel()
        robot.world_model = model  # type: ignore[attr-defined]
    return model


# --- the built-ins ---------------------------------------------------------------------------------


_builtin = registrar(WORLD)


def _name(stmt: Stmt, value: Any, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise ScriptFault(
            f"{stmt.name}: {what} must be a frame's name (a text), not {type_name(value)}",
            stmt.line,
            stmt.column or 1,
        )
    return value


def _do(stmt: Stmt, action: Callable[[], Any]) -> Any:
    try:
        return action()
    except FrameError as refused:
        raise ScriptFault(f"{stmt.name}: {refused}", stmt.line, stmt.column or 1) from None


def _transform(stmt: Stmt, value: Any) -> Transform:
    return from_pose(six(stmt, value, "pose"))


@_builtin("add_frame", "move_frame")
def _place(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    first = "name" if stmt.name == "add_frame" else "frame"
    name = _name(stmt, arg(stmt, args, kwargs, 0, first), first)
    pose = _transform(stmt, arg(stmt, args, kwargs, 1, "pose"))
    ref = _name(stmt, arg(stmt, args, kwargs, 2, "ref_frame", "base"), "ref_frame")
    world, arm = world_of(runner.robot), runner.robot.arm
    _do(stmt, lambda: (world.add if stmt.name == "add_frame" else world.move)(name, pose, ref, arm))


@_builtin("attach_frame")
def _attach(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    child = _name(stmt, arg(stmt, args, kwargs, 0, "child"), "child")
    parent = _name(stmt, arg(stmt, args, kwargs, 1, "parent"), "parent")
    _do(stmt, lambda: world_of(runner.robot).attach(child, parent, runner.robot.arm))


@_builtin("delete_frame")
def _delete(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    name = _name(stmt, arg(stmt, args, kwargs, 0, "frame"), "frame")
    _do(stmt, lambda: world_of(runner.robot).delete(name, runner.robot.arm))


@_builtin("delete_all_frames")
def _delete_all(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    world_of(runner.robot).delete_all(runner.robot.arm)


@_builtin("reset_world_model")
def _reset(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    world_of(runner.robot).reset()


@_builtin("get_frame_parent")
def _parent(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> str:
    name = _name(stmt, arg(stmt, args, kwargs, 0, "frame"), "frame")
    parent: str = _do(stmt, lambda: world_of(runner.robot).parent(name))
    return parent


@_builtin("get_pose")
def _get_pose(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    name = _name(stmt, arg(stmt, args, kwargs, 0, "frame"), "frame")
    ref = _name(stmt, arg(stmt, args, kwargs, 1, "ref_frame", "base"), "ref_frame")
    world, arm = world_of(runner.robot), runner.robot.arm
    return to_pose(_do(stmt, lambda: world.pose(name, ref, arm)))


@_builtin("convert_pose")
def _convert(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Pose:
    pose = _transform(stmt, arg(stmt, args, kwargs, 0, "pose"))
    source = _name(stmt, arg(stmt, args, kwargs, 1, "from_frame"), "from_frame")
    target = _name(stmt, arg(stmt, args, kwargs, 2, "to_frame"), "to_frame")
    world, arm = world_of(runner.robot), runner.robot.arm
    return to_pose(_do(stmt, lambda: world.convert(pose, source, target, arm)))
