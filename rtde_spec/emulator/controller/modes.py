"""Power, brakes, safety stops and program control: what the dashboard (and scenarios) ask of the robot.

Each request sets robot_mode, safety_mode/safety_status, their bits, joint modes and
runtime_state through the generated enums, and answers whether it was accepted,
so the dashboard server can give the controller's reply text. A robot that is
powered off, braked or safety-stopped does not move and runs no program.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.enums import (
    JointMode,
    ProgramState,
    RobotMode,
    RobotStatusBits,
    SafetyMode,
    SafetyStatus,
    SafetyStatusBits,
)
from rtde_spec.emulator.arm.motion import MOVEJ_A
from rtde_spec.printable import safe_text

# s a protective stop lasts before the dashboard unlocks it ("Cannot unlock protective stop until 5s
# after occurrence"). The primary port's `set unlock protective stop` is done at once: URCL's tests
# against URSim send it right after a stop and expect the stop gone within their 5 s wait
# (tests/test_primary_client.cpp 511-521, 552-562, 579-588), a deferred unlock missed that.
UNLOCK_AFTER = 5.0

if TYPE_CHECKING:
    from rtde_spec.emulator.arm.state import Arm
    from rtde_spec.emulator.controller.program import Program
    from rtde_spec.emulator.urscript.events import ScriptEvent

log = logging.getLogger("rtde_spec.emulator")


class RobotModes:
    """Mixed into ControllerModel: the state machine of power, brakes, safety and the program."""

    values: dict[str, Any]
    time: float
    base_hz: float
    protective_stop_at: float | None = None  # model time of the current protective stop
    arm: Arm
    program: Program | None
    paused: bool
    loaded: str | None
    simulated = False  # `set sim` on a script port: the real arm is not enabled (Robot Mode Data says so)

    def run_script(self, text: str) -> Program | None:
        raise NotImplementedError

    def start_loaded(self) -> bool:
        raise NotImplementedError

    def emit(self, event: ScriptEvent) -> None:
        raise NotImplementedError

    def _end_program(self) -> None:
        raise NotImplementedError

    # --- what the state allows ------------------------------------------------

    @property
    def robot_mode(self) -> int:
        return int(self.values.get("robot_mode", RobotMode.RUNNING))

    @property
    def safety_mode(self) -> int:
        return int(self.values.get("safety_mode", SafetyMode.NORMAL))

    def can_move(self) -> bool:
        """Powered, brakes released, no safety stop."""
        return self.robot_mode == RobotMode.RUNNING and self.safety_mode in (
            SafetyMode.NORMAL,
            SafetyMode.REDUCED,
        )

    @property
    def program_state(self) -> ProgramState:
        if self.program is None:
            return ProgramState.STOPPED
        return ProgramState.PAUSED if self.paused else ProgramState.RUNNING

    # --- power and brakes -------------------------------------------------------

    def power_on(self) -> bool:
        """Power the arm: IDLE with the brakes on (as after the controller's POWER_ON phase)."""
        if self.robot_mode in (RobotMode.IDLE, RobotMode.RUNNING):
            return True
        self._set("robot_mode", RobotMode.IDLE)
        self._bits("robot_status_bits", RobotStatusBits.POWER_ON, True)
        self._joints(JointMode.IDLE)
        return True

    def power_off(self) -> bool:
        """Cut arm power: the arm stands where it is, the program stops."""
        self.arm.halt()
        if self.program is not None:
            self._end_program()
        self._set("robot_mode", RobotMode.POWER_OFF)
        self._bits("robot_status_bits", RobotStatusBits.POWER_ON, False)
        self._joints(JointMode.POWER_OFF)
        return True

    def release_brakes(self) -> bool:
        """IDLE -> RUNNING; refused while powered off."""
        if self.robot_mode == RobotMode.RUNNING:
            return True
        if self.robot_mode != RobotMode.IDLE:
            return False
        self._set("robot_mode", RobotMode.RUNNING)
        self._joints(JointMode.RUNNING)
        return True

    # --- safety -----------------------------------------------------------------

    def stopped_on_the_way(self, why: str) -> None:
        """A move that leaves the arm's reach on the way: a protective stop, the program paused at
        its move, as URSim does (URCL's tests wait for one: test_instruction_executor.cpp)."""
        name = self.program.name if self.program is not None else ""
        log.warning("program %s: %s: protective stop", safe_text(name), safe_text(why[:200]))
        self.protective_stop()

    def protective_stop(self) -> bool:
        """Halt at once and pause the program until unlocked and played again.

        The stop counts from the step before this one: a client sees the step's state as soon as it
        is computed (the dashboard reads it), up to a step before the step's time."""
        if self.safety_mode != SafetyMode.PROTECTIVE_STOP:
            self.protective_stop_at = self.time - 1.0 / self.base_hz
        if self.program is None:
            self.arm.halt()
        else:  # the motion is kept, frozen, and goes on when the program is played again
            self.paused = True
            self._program_bits()
        self._safety(
            SafetyMode.PROTECTIVE_STOP, SafetyStatus.PROTECTIVE_STOP, SafetyStatusBits.PROTECTIVE_STOPPED
        )
        return True

    def unlock_wait(self) -> float:
        """Seconds before the current protective stop may be unlocked (0: now, or no stop)."""
        if self.safety_mode != SafetyMode.PROTECTIVE_STOP or self.protective_stop_at is None:
            return 0.0
        return max(0.0, self.protective_stop_at + UNLOCK_AFTER - self.time)

    def unlock_protective_stop(self) -> bool:
        """PROTECTIVE_STOP -> NORMAL (the dashboard asks unlock_wait() first)."""
        if self.safety_mode != SafetyMode.PROTECTIVE_STOP:
            return False
        self._safety(SafetyMode.NORMAL, SafetyStatus.NORMAL, SafetyStatusBits.NORMAL_MODE)
        return True

    # --- the program --------------------------------------------------------------

    def simulate(self, on: bool) -> bool:
        """`set sim` / `set real`: the program runs on the simulated arm or the real one; the Robot
        Mode Data's isRealRobotEnabled says which (the emulator's arm moves the same either way)."""
        self.simulated = on
        return True

    def load_program(self, text: str) -> None:
        """Keep a program (URScript text) for play()."""
        self.loaded = text

    def play(self) -> bool:
        """Resume a paused program, or start the loaded one; refused when the arm cannot move."""
        if not self.can_move():
            return False
        if self.program is not None and self.paused:
            self.paused = False
            self._program_bits()
            return True
        if self.program is not None:
            return True
        return self.loaded is not None and self.start_loaded()

    def pause_program(self) -> bool:
        if self.program is None:
            return False
        self.paused = True
        self._program_bits()
        return True

    def stop_program(self) -> bool:
        """End the program; a moving arm decelerates (stop category 2)."""
        if self.program is None:
            return False
        frozen = self.paused or not self.can_move()
        self.program.finished = True
        self._end_program()
        if frozen:
            self.arm.halt()
        elif self.arm.moving:
            self.arm.stop(MOVEJ_A)
        return True

    # --- how the outputs show it ----------------------------------------------------

    def _program_bits(self) -> None:
        self._set("runtime_state", self.program_state)
        running = self.program is not None and not self.paused
        self._bits("robot_status_bits", RobotStatusBits.PROGRAM_RUNNING, running)

    def _safety(self, mode: SafetyMode, status: SafetyStatus, bits: SafetyStatusBits) -> None:
        self._set("safety_mode", mode)
        self._set("safety_status", status)
        self._set("safety_status_bits", bits)

    def _joints(self, mode: JointMode) -> None:
        if "joint_mode" in self.values:
            self.values["joint_mode"] = (int(mode),) * 6

    def _set(self, name: str, value: int) -> None:
        if name in self.values:
            self.values[name] = int(value)

    def _bits(self, name: str, bit: int, on: bool) -> None:
        if name in self.values:
            current = int(self.values[name])
            self.values[name] = (current | int(bit)) if on else (current & ~int(bit))
