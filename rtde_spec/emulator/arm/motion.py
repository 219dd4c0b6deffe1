"""Motions the emulated arm runs: trapezoidal profiles in joint or Cartesian space, speeds, stops.

Each motion starts from the arm's state and answers `step(dt)` with the next joint
positions, velocities and accelerations. `dt` is trajectory time: the model scales
real time by the speed slider before it asks, as a controller slows a program down.
Defaults follow the Script manual: movej a=1.4 rad/s² v=1.05 rad/s, movel a=1.2 m/s²
v=0.25 m/s. Joint speeds never exceed the arm's published maxima.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.errors import UsageError
from rtde_spec.metamodel.arms import ArmModel

MOVEJ_A, MOVEJ_V = 1.4, 1.05
MOVEL_A, MOVEL_V = 1.2, 0.25
TIME_SLACK = 1e-9  # s: a motion this close to its end is done (float sums of its steps)
Vec = NDArray[np.float64]
Floats = kin.Floats


class MotionError(Exception):
    """A motion the controller cannot run (out of reach, over a joint limit); becomes a runtime exception."""


@dataclass(frozen=True)
class Profile:
    """Trapezoidal (or, when too short to cruise, triangular) profile over `distance` ≥ 0."""

    distance: float
    v: float
    a: float
    t_acc: float
    t_flat: float

    @property
    def duration(self) -> float:
        return 2 * self.t_acc + self.t_flat

    def at(self, t: float) -> tuple[float, float, float]:
        """(position, velocity, acceleration) at time t, clamped to the ends."""
        ta, tf, a = self.t_acc, self.t_flat, self.a
        if self.distance <= 0 or t >= self.duration:
            return self.distance, 0.0, 0.0
        if t <= 0:
            return 0.0, 0.0, 0.0
        if t < ta:
            return 0.5 * a * t * t, a * t, a
        if t < ta + tf:
            return 0.5 * a * ta * ta + self.v * (t - ta), self.v, 0.0
        rest = self.duration - t
        return self.distance - 0.5 * a * rest * rest, a * rest, -a


def profile(distance: float, v: float, a: float, t: float = 0.0) -> Profile:
    """The profile that covers `distance` with top speed v and acceleration a, or in time t if t > 0."""
    distance, v, a = abs(distance), max(abs(v), 1e-9), max(abs(a), 1e-9)
    if distance <= 0:
        return Profile(0.0, v, a, 0.0, 0.0)
    if t > 0:
        disc = a * a * t * t - 4 * a * distance
        if disc >= 0:  # cruise at the speed that makes the move last t
            v = (a * t - math.sqrt(disc)) / 2
        else:  # too short a time for this a: a triangle that lasts t
            a, v = 4 * distance / (t * t), 2 * distance / t
    t_acc = v / a
    if a * t_acc * t_acc >= distance:  # never reaches v: triangle
        t_acc = math.sqrt(distance / a)
        return Profile(distance, a * t_acc, a, t_acc, 0.0)
    return Profile(distance, v, a, t_acc, (distance - a * t_acc * t_acc) / v)


@dataclass
class State:
    q: Vec
    qd: Vec
    qdd: Vec


def rest(q: Floats) -> State:
    return State(np.array(q, dtype=float), np.zeros(6), np.zeros(6))


class Motion:
    """Base: a motion owns its clock; `done` once finished; `remaining` path left (for blending)."""

    blend: float = 0.0
    line: int = 0  # the script line that started it, for a fault on the way
    holds: bool = False  # speedj/speedl keep their velocity after the call returns
    ends_moving: bool = False  # the step that ends it reports its speed; the arm rests a step later
    thread_late: Callable[[], bool] | None = None  # its program thread still late for its next command
    hold: float = 0.0  # s a speed asked for (speedj/speedl's t; 0: until its ramp ends)
    step_dt: float = 0.0  # the trajectory time of its last step

    def __init__(self, start: State) -> None:
        self.start, self.t, self.last = start, 0.0, start

    def follow(self, last: Motion) -> None:
        """Start after `last`. A held speed's time ends inside a step when the speed slider is not
        1 (a speedj of 2 ms at 0.49 is 2.04 steps): the part of its last step past that time counts
        against this speed's own, so a program's speeds last what it asked for in sum. Each of URCL's
        spline speedjs ran 3 steps at 0.49, its spline went 1.47x as far, to wrist 3's limit."""
        over = last.t - last.duration
        if self.holds and self.hold > 0 and last.holds and 0 < over <= last.step_dt:
            self.hold = max(self.hold - over, TIME_SLACK)

    @property
    def overdue(self) -> bool:
        """A held speed past the time its call asked for, while the thread that commanded it,
        preempted on a loaded machine, has not reached its next command: the arm waits for the
        thread (a controller's is there in time) instead of running the speed on. URCL's spline
        is one speedj per step: each step the program was late moved the arm a step too far, and
        its QUINTIC example took wrist 3 to its 2π limit instead of 5.41 rad."""
        return self.holds and self.done and self.thread_late is not None and self.thread_late()

    def step(self, dt: float) -> State:
        self.t, self.step_dt = self.t + dt, dt
        self.last = self.sample(self.t)
        return self.last

    def sample(self, t: float) -> State:
        raise NotImplementedError

    @property
    def done(self) -> bool:
        """Its time is over. Slack for the sum of steps: a speed slider of 1 - 50 x 0.01 (URCL's
        rtde_client example leaves 0.49999999999999956) made two steps of a speedj of one step
        fall short of it, and each speedj of URCL's spline ran a third step: the spline went 1.5x
        as far, to wrist 3's limit."""
        return self.t >= self.duration - TIME_SLACK

    @property
    def duration(self) -> float:
        return 0.0

    @property
    def remaining(self) -> float:
        return 0.0


class JointMove(Motion):
    """movej: every joint starts and stops together, the farthest one on the profile."""

    def __init__(self, arm: ArmModel, start: State, target: Floats, a: float, v: float, t: float) -> None:
        super().__init__(start)
        check_limits(arm, target)
        self.delta = np.array(target, dtype=float) - start.q
        lead = float(np.max(np.abs(self.delta)))
        # the lead joint's speed, lowered so no joint passes its own maximum
        pairs = zip(arm.max_joint_speed, self.delta, strict=True)
        ratios = [mx * lead / abs(d) for mx, d in pairs if abs(d) > 1e-12]
        self.profile = profile(lead, min([v, *ratios]), a, t)
        self.lead = lead

    def sample(self, t: float) -> State:
        if self.lead <= 0:
            return State(self.start.q.copy(), np.zeros(6), np.zeros(6))
        s, sd, sdd = self.profile.at(t)
        unit = self.delta / self.lead
        return State(self.start.q + unit * s, unit * sd, unit * sdd)

    @property
    def duration(self) -> float:
        return self.profile.duration

    @property
    def remaining(self) -> float:
        return self.lead - self.profile.at(self.t)[0]


class LinearMove(Motion):
    """movel/movep: the TCP on a straight line (orientation turned about one axis), joints by IK."""

    def __init__(
        self, arm: ArmModel, tcp: Floats, start: State, target: Floats, a: float, v: float, t: float
    ) -> None:
        super().__init__(start)
        self.arm, self.tcp = arm, tuple(tcp)
        here = kin.forward(arm, start.q, tcp)
        self.p0 = np.array(here[:3])
        self.dp = np.array([float(v) for v in target[:3]]) - self.p0
        self.r0 = kin.rotvec_to_rot(here[3:])
        self.turn = np.array(
            kin.matrix_to_rotvec(kin.mul(kin.transpose(self.r0), kin.rotvec_to_rot(target[3:])))
        )
        length, angle = float(np.linalg.norm(self.dp)), float(np.linalg.norm(self.turn))
        self.length = length if length > 1e-6 else angle  # a pure turn runs at v in rad/s
        # a target out of reach is not refused here: the arm goes along the line and stops where
        # the line leaves its reach (`sample`). PolyScope's Direction node moves towards a point
        # 1000 m away until a condition kills the move (`calculate_point_to_move_towards`).
        self.profile = profile(self.length, v, a, t)
        self.q, self._t_prev = start.q.copy(), 0.0

    def pose_at(self, s: float) -> list[float]:
        f = s / self.length if self.length > 0 else 1.0
        rot = kin.mul(self.r0, kin.rotvec_to_rot(self.turn * f))
        return [*(float(v) for v in self.p0 + self.dp * f), *kin.matrix_to_rotvec(rot)]

    def sample(self, t: float) -> State:
        s = self.profile.at(t)[0]
        try:
            q = np.array(kin.nearest(self.arm, self.pose_at(s), self.q, self.tcp, same_branch=True))
        except UsageError as exc:  # a singular point, or the edge of the arm's reach, on the way
            raise MotionError(f"inverse kinematics failed on the way: {exc.reason}") from exc
        previous = self.last
        dt = max(t - self._t_prev, 1e-9)
        qd = (q - previous.q) / dt
        qdd = (qd - previous.qd) / dt
        self.q, self._t_prev = q, t
        return State(q, qd, qdd)

    @property
    def duration(self) -> float:
        return self.profile.duration

    @property
    def remaining(self) -> float:
        return self.length - self.profile.at(self.t)[0]


class JointSpeed(Motion):
    """speedj: every joint's speed ramps to its target with acceleration a, together; then holds."""

    holds = True

    def __init__(self, arm: ArmModel, start: State, qd: Floats, a: float, t: float) -> None:
        super().__init__(start)
        limit = np.array(arm.max_joint_speed)
        self.target = np.clip(np.array(qd, dtype=float), -limit, limit)
        change = self.target - start.qd
        self.ramp = float(np.max(np.abs(change))) / max(abs(a), 1e-9)
        self.change, self.hold, self.a = change, t, a

    def sample(self, t: float) -> State:
        if self.ramp > 0 and t < self.ramp:
            f = t / self.ramp
            qd = self.start.qd + self.change * f
            q = self.start.q + self.start.qd * t + self.change * (t * t / (2 * self.ramp))
            return State(q, qd, self.change / self.ramp)
        q_ramp = self.start.q + (self.start.qd + self.change / 2) * self.ramp
        return State(q_ramp + self.target * (t - self.ramp), self.target.copy(), np.zeros(6))

    @property
    def duration(self) -> float:
        return self.hold if self.hold > 0 else self.ramp


class LinearSpeed(Motion):
    """speedl: the TCP's velocity (m/s, rad/s in Base) ramps to its target, then holds; joints by IK."""

    holds = True

    def __init__(self, arm: ArmModel, tcp: Floats, start: State, xd: Floats, a: float, t: float) -> None:
        super().__init__(start)
        self.arm, self.tcp, self.hold, self.a = arm, tuple(tcp), t, a
        self.pose = kin.pose_to_matrix(kin.forward(arm, start.q, tcp))
        self.target = np.array(xd, dtype=float)
        self.initial = _tool_speed(arm, tcp, start)  # a speedl after a speedl goes on from its speed
        self.ramp = float(np.linalg.norm(self.target[:3] - self.initial[:3])) / max(abs(a), 1e-9)
        self.q = start.q.copy()

    def step(self, dt: float) -> State:
        self.t, self.step_dt = self.t + dt, dt
        f = min(1.0, self.t / self.ramp) if self.ramp > 0 else 1.0
        xd = self.initial + (self.target - self.initial) * f
        self.pose[:3, 3] += xd[:3] * dt
        self.pose[:3, :3] = kin.rotvec_to_matrix(xd[3:] * dt) @ self.pose[:3, :3]
        try:
            q = np.array(
                kin.nearest(self.arm, kin.matrix_to_pose(self.pose), self.q, self.tcp, same_branch=True)
            )
        except UsageError as exc:
            raise MotionError(f"speedl left the workspace: {exc.reason}") from exc
        qd = (q - self.q) / max(dt, 1e-9)
        self.last = State(q, qd, (qd - self.last.qd) / max(dt, 1e-9))
        self.q = q
        return self.last

    @property
    def duration(self) -> float:
        return self.hold if self.hold > 0 else self.ramp


def _tool_speed(arm: ArmModel, tcp: Floats, start: State) -> np.ndarray:
    """The TCP's velocity (m/s, rad/s in Base) at the joints' speeds `start.qd`."""
    if not np.any(start.qd):
        return np.zeros(6)
    h = 1e-6
    now = kin.pose_to_matrix(kin.forward(arm, start.q, tcp))
    later = kin.pose_to_matrix(kin.forward(arm, start.q + start.qd * h, tcp))
    turn = later[:3, :3] @ now[:3, :3].T
    rot = kin.matrix_to_pose(np.block([[turn, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]))[3:]
    return np.concatenate([(later[:3, 3] - now[:3, 3]) / h, np.array(rot) / h])


class Servo(Motion):
    """servoj: straight to q over time t (the controller's own smoothing is not modelled).

    The step that reaches q still moved at the servo's speed, and reports it (`ends_moving`):
    a stream of servoj, each reached within its step, is an arm moving at the stream's speed,
    not one standing still (actual_qd and the TCP speed were 0 all through such a stream)."""

    ends_moving = True

    def __init__(self, start: State, target: Floats, t: float) -> None:
        super().__init__(start)
        self.target, self.span = np.array(target, dtype=float), max(t, 1e-9)

    def sample(self, t: float) -> State:
        f = min(1.0, t / self.span)
        qd = (self.target - self.start.q) / self.span
        return State(self.start.q + (self.target - self.start.q) * f, qd, np.zeros(6))

    @property
    def duration(self) -> float:
        return self.span


class Stop(Motion):
    """stopj/stopl and the end of a program: every joint's speed falls to 0 together."""

    def __init__(self, start: State, span: float) -> None:
        super().__init__(start)
        self.span = max(span, 0.0)

    def sample(self, t: float) -> State:
        if self.span <= 0 or t >= self.span:
            q = self.start.q + self.start.qd * self.span / 2
            return State(q, np.zeros(6), np.zeros(6))
        qd = self.start.qd * (1 - t / self.span)
        q = self.start.q + self.start.qd * t - self.start.qd * t * t / (2 * self.span)
        return State(q, qd, -self.start.qd / self.span)

    @property
    def duration(self) -> float:
        return self.span


def stop_joints(start: State, a: float) -> Stop:
    return Stop(start, float(np.max(np.abs(start.qd))) / max(abs(a), 1e-9))


def stop_linear(arm: ArmModel, tcp: Floats, start: State, a: float) -> Stop:
    """Decelerate so the TCP's speed falls at a (m/s²); the joints keep their ratios."""
    here = np.array(kin.forward(arm, start.q, tcp)[:3], dtype=float)
    ahead = np.array(kin.forward(arm, start.q + start.qd * 1e-3, tcp)[:3], dtype=float)
    speed = float(np.linalg.norm(ahead - here)) / 1e-3
    return Stop(start, speed / max(abs(a), 1e-9))


def check_limits(arm: ArmModel, q: Floats) -> None:
    for i, (value, (low, high)) in enumerate(zip(q, arm.joint_limits, strict=True)):
        if not low - 1e-9 <= value <= high + 1e-9:
            raise MotionError(
                f"joint {i} target {value:.4f} rad is outside the {arm.name}'s range [{low:.4f}, {high:.4f}]"
            )
