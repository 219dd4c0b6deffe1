"""The emulated arm: joint state, the motion it runs, and the TCP pose and speed its joints give.

Kept apart from the controller model so motion and kinematics can be tested on
their own; the model writes what this holds into its outputs every control step.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.arm.motion import MOVEJ_A, LinearSpeed, Motion, State, rest, stop_joints, stop_linear
from rtde_spec.metamodel.arms import ArmModel

LIMIT_SLACK = 1e-9  # rad past a joint limit still counted as at it (a move that ends on it)
SPEED_STEP = 1e-4  # s: TCP speed is the pose change over this much joint motion


class Arm:
    """Joint state plus the current motion; `step(dt)` moves it on by trajectory time dt."""

    def __init__(self, model: ArmModel, q: Sequence[float]) -> None:
        self.model = model
        self.state = rest(q)
        self.tcp: tuple[float, ...] = (0.0,) * 6
        self.motion: Motion | None = None
        self.revision = 0  # counts changes of the joint state, so an arm at rest is not re-published
        self._pose_cache: tuple[tuple[float, ...], tuple[float, ...], kin.Pose] | None = None

    @property
    def moving(self) -> bool:
        return self.motion is not None

    def move(self, motion: Motion) -> None:
        if self.motion is not None and self.motion.done:
            motion.follow(self.motion)  # a held speed's time past its end counts against the next's
        self.motion = motion

    def step(self, dt: float) -> None:
        """Advance the motion; a finished one (not a held speed) leaves the arm at rest (a servo
        target reached: at the next step, unless another servoj came)."""
        if self.motion is None:
            if self.state.qd.any():  # a servo target reached last step, and no new one
                self.state = rest(self.state.q)
                self.revision += 1
            return
        if self.motion.overdue:  # a held speed waits for its late thread's next command
            return
        self.revision += 1
        self.state = self.motion.step(dt)
        if self.motion.done and not self.motion.holds:
            if not self.motion.ends_moving:
                self.state = rest(self.state.q)
            self.motion = None

    def halt(self) -> None:
        """Stand still at once (power loss, protective stop): no deceleration."""
        self.motion = None
        self.state = rest(self.state.q)
        self.revision += 1

    def stop(self, a: float = MOVEJ_A, linear: bool = False) -> None:
        """Decelerate from the current velocity (stopj, stopl, the end of a program)."""
        if not np.any(self.state.qd):
            self.halt()
            return
        if linear or isinstance(self.motion, LinearSpeed):
            self.motion = stop_linear(self.model, self.tcp, self.state, a)
        else:
            self.motion = stop_joints(self.state, a)

    def over_limit(self) -> int | None:
        """The first joint past its position limit (the arm model's), if any."""
        for i, (value, (low, high)) in enumerate(zip(self.state.q, self.model.joint_limits, strict=True)):
            if not low - LIMIT_SLACK <= value <= high + LIMIT_SLACK:
                return i
        return None

    def place(self, q: Sequence[float]) -> None:
        """Joints set from outside (a scenario): at rest there."""
        self.motion = None
        self.state = rest(q)
        self.revision += 1

    def pose(self, q: kin.Floats | None = None) -> kin.Pose:
        """FK of q (default: the arm's joints) with the TCP offset; the last answer is cached."""
        key = tuple(float(v) for v in (self.state.q if q is None else q))
        cached = self._pose_cache
        if cached is not None and cached[0] == key and cached[1] == self.tcp:
            return cached[2]
        pose = kin.forward(self.model, key, self.tcp)
        self._pose_cache = (key, self.tcp, pose)
        return pose

    def tcp_speed(self, state: State | None = None) -> tuple[float, ...]:
        """TCP velocity in Base (m/s, then rad/s as a rotation vector rate) at the joints' speed."""
        state = state or self.state
        if not np.any(state.qd):
            return (0.0,) * 6
        r0, p0 = kin.tcp_frame(self.model, state.q, self.tcp)
        r1, p1 = kin.tcp_frame(self.model, state.q + state.qd * SPEED_STEP, self.tcp)
        w = kin.matrix_to_rotvec(kin.mul(r1, kin.transpose(r0)))
        h = SPEED_STEP
        return ((p1[0] - p0[0]) / h, (p1[1] - p0[1]) / h, (p1[2] - p0[2]) / h, w[0] / h, w[1] / h, w[2] / h)
