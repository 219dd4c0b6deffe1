"""Generated enums carry the guides' values and docs."""

from __future__ import annotations

from rtde_spec._generated.enums import (
    VALUE_DOCS,
    JointMode,
    RobotMode,
    RobotStatusBits,
    SafetyStatus,
    SafetyStatusBits,
    TimeScaleSource,
)
from rtde_spec.output.describe import describe


def test_values_from_the_guides() -> None:
    assert RobotMode.RUNNING == 7 and RobotMode(11).name == "ARM_UPDATING"
    assert JointMode.BOOTLOADER == 249 and JointMode.IDLE == 255
    assert SafetyStatus.SAFETY_API_SAFEGUARD_STOP == 22
    assert TimeScaleSource.OTHER == -1
    assert SafetyStatusBits.THREE_POSITION_ENABLING_INPUT_ACTIVE == 1 << 11
    assert RobotStatusBits.POWER_ON | RobotStatusBits.PROGRAM_RUNNING == 3


def test_per_value_docs() -> None:
    assert "safety control board" in VALUE_DOCS["RobotMode"][0]
    assert RobotMode.__doc__ and "robot_mode" in RobotMode.__doc__


def test_describe_names_values_and_bits() -> None:
    assert describe(7, "RobotMode") == "7 (RUNNING)"
    assert describe(99, "RobotMode") == "99 (unlisted)"
    assert describe(0b101, bits="RobotStatusBits") == "0x5 (POWER_ON|TEACH_BUTTON_PRESSED)"
