"""Faults a scenario schedules: what goes wrong on a controller, at a time, for a while.

    faults:
      - {at: 2.0, fault: protective_stop}
      - {at: 4.0, fault: network_drop, seconds: 3}
      - {at: 9.0, fault: emergency_stop, seconds: 2}
      - {at: 12.0, fault: power_loss}
      - {at: 14.0, fault: program_stop}
      - {at: 16.0, fault: joint_limit, joint: 5}

`at` is controller time (s since start). A protective stop halts the arm and pauses
its program until unlocked (dashboard `unlock protective stop`); an emergency stop
cuts arm power and holds the safety mode until released (after `seconds`, if given;
the arm stays powered off, as after a real one); a power loss cuts arm power; a
program stop ends the program as a client's stop does; a joint limit hit puts `joint`
(0 = base, default 0) at its nearer position limit (the arm model's) and reacts as when
a motion reaches one: the arm stops there, a protective stop, a runtime exception
message naming the joint; a network drop silences every
port for `seconds` (nothing sent, nothing read; connections stay open, as with a
pulled cable) and then resumes. The safety and mode changes reach RTDE, the primary
ports (with their safety mode message) and the dashboard through the same model.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any, Literal

from pydantic import BaseModel, ConfigDict, Field

from rtde_spec._generated.enums import SafetyMode, SafetyStatus, SafetyStatusBits

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel

log = logging.getLogger("rtde_spec.emulator")
FaultKind = Literal[
    "protective_stop", "emergency_stop", "power_loss", "program_stop", "network_drop", "joint_limit"
]


class Fault(BaseModel):
    model_config = ConfigDict(extra="forbid")

    at: float = Field(ge=0)
    fault: FaultKind
    seconds: float | None = Field(default=None, gt=0)  # how long (network drop, emergency stop)
    joint: int = Field(default=0, ge=0, le=5)  # which joint hits its limit (joint_limit)


class FaultSchedule:
    """The scenario's faults in time order; `apply(t)` runs those due, and ends timed ones."""

    def __init__(self, faults: list[Fault], model: ControllerModel) -> None:
        self.pending = sorted(faults, key=lambda f: f.at)
        self.model = model
        self.silent_until = -1.0  # controller time the network drop ends
        self._release_at: float | None = None  # of an emergency stop

    def silent(self, t: float) -> bool:
        """Whether the network is down at controller time t."""
        return t < self.silent_until

    def apply(self, t: float) -> bool:
        """Run what is due at t; True when something changed (the servers then look again)."""
        changed = False
        if self._release_at is not None and t >= self._release_at:
            self._release_at = None
            self._safety(SafetyMode.NORMAL, SafetyStatus.NORMAL, SafetyStatusBits.NORMAL_MODE)
            log.info("scenario: emergency stop released at %.3f s", t)
            changed = True
        while self.pending and self.pending[0].at <= t:
            fault = self.pending.pop(0)
            log.info("scenario: %s at %.3f s", fault.fault, t)
            self._run(fault, t)
            changed = True
        return changed

    def _run(self, fault: Fault, t: float) -> None:
        model: Any = self.model  # the mode methods of ControllerModel (emulator/controller/modes.py)
        kind = fault.fault
        if kind == "protective_stop":
            model.protective_stop()
        elif kind == "power_loss":
            model.power_off()
        elif kind == "program_stop":
            model.stop_program()
        elif kind == "emergency_stop":
            model.power_off()
            self._safety(
                SafetyMode.ROBOT_EMERGENCY_STOP,
                SafetyStatus.ROBOT_EMERGENCY_STOP,
                SafetyStatusBits.ROBOT_EMERGENCY_STOPPED | SafetyStatusBits.EMERGENCY_STOPPED,
            )
            self._release_at = t + fault.seconds if fault.seconds else None
        elif kind == "joint_limit":
            arm = model.arm
            low, high = arm.model.joint_limits[fault.joint]
            q = [float(v) for v in arm.state.q]
            q[fault.joint] = high if abs(high - q[fault.joint]) <= abs(q[fault.joint] - low) else low
            arm.place(q)
            model.joint_limit_hit(fault.joint)
        elif kind == "network_drop":
            self.silent_until = t + (fault.seconds or 1.0)

    def _safety(self, mode: int, status: int, bits: int) -> None:
        values = self.model.values
        for name, value in (("safety_mode", mode), ("safety_status", status), ("safety_status_bits", bits)):
            if name in values:
                values[name] = int(value)
