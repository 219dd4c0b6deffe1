"""The emulated controller's state: every output the version has, moved by time and inputs.

Defaults describe a powered robot in RUNNING mode with no program; the timestamp
advances with the control steps; a scenario sets outputs as constants or functions
of time; inputs change the outputs a real controller reflects them in (digital and
analog outputs, the speed slider, and every input register's read-back).
Enum values and bit positions come from the generated spec tables.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from rtde_spec._generated.enums import (
    AnalogIoTypes,
    DigitalIoBits,
    JointMode,
    ProgramState,
    RobotMode,
    RobotStatusBits,
    SafetyMode,
    SafetyStatus,
    SafetyStatusBits,
    StandardAnalogOutputBits,
)
from rtde_spec.spec.catalogue import Catalogue, FieldInfo
from rtde_spec.spec.versions import Version

HOME_Q = (0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0)
DEFAULTS: dict[str, Any] = {
    "robot_mode": int(RobotMode.RUNNING),
    "safety_mode": int(SafetyMode.NORMAL),
    "safety_status": int(SafetyStatus.NORMAL),
    "runtime_state": int(ProgramState.STOPPED),
    "joint_mode": (int(JointMode.RUNNING),) * 6,
    "robot_status_bits": int(RobotStatusBits.POWER_ON),
    "safety_status_bits": int(SafetyStatusBits.NORMAL_MODE),
    "speed_scaling": 1.0,
    "target_speed_fraction": 1.0,
    "actual_q": HOME_Q,
    "target_q": HOME_Q,
    "joint_temperatures": (30.0,) * 6,
    "actual_main_voltage": 48.0,
    "actual_robot_voltage": 48.0,
}
# where each group of digital outputs starts in actual_digital_output_bits
_SHIFT = {
    "standard": DigitalIoBits.STANDARD_0.bit_length() - 1,
    "configurable": DigitalIoBits.CONFIGURABLE_0.bit_length() - 1,
    "tool": DigitalIoBits.TOOL_0.bit_length() - 1,
}
_ANALOG_OUT_VOLTAGE = (AnalogIoTypes.ANALOG_OUTPUT_0_VOLTAGE, AnalogIoTypes.ANALOG_OUTPUT_1_VOLTAGE)
_ANALOG_OUT_SELECT = (
    StandardAnalogOutputBits.STANDARD_ANALOG_OUTPUT_0,
    StandardAnalogOutputBits.STANDARD_ANALOG_OUTPUT_1,
)


def _zero(info: FieldInfo) -> Any:
    one: Any = {"float": 0.0, "int": 0, "bool": False}[info.wire.kind]
    return one if info.wire.count == 1 else (one,) * info.wire.count


class ControllerModel:
    """Output values by name, for one controller version."""

    def __init__(
        self,
        version: str,
        catalogue: Catalogue | None = None,
        functions: Mapping[str, Callable[[float], Any]] | None = None,
    ) -> None:
        self.catalogue = catalogue or Catalogue.default()
        self.version = Version.parse(version)
        self.line = self.catalogue.line_of(self.version)
        self.base_hz = self.line.rtde_max_frequency
        self.outputs = {i.name: i for i in self.catalogue.fields("output", self.version)}
        self.inputs = {i.name: i for i in self.catalogue.fields("input", self.version)}
        self.values: dict[str, Any] = {n: DEFAULTS.get(n, _zero(i)) for n, i in self.outputs.items()}
        self.functions = dict(functions or {})
        self.step = 0
        self.time = 0.0
        self.tick(0)

    def tick(self, step: int) -> None:
        """Move to control step `step`: the timestamp, then every scenario function."""
        self.step = step
        self.time = step / self.base_hz
        values = self.values
        if "timestamp" in values:
            values["timestamp"] = self.time
        for name, fn in self.functions.items():
            values[name] = fn(self.time)

    def apply_inputs(self, inputs: Mapping[str, Any]) -> None:
        """A data package from a client: read-backs, then what the outputs reflect."""
        values = self.values
        for name, value in inputs.items():
            if name in values and name not in self.functions:
                values[name] = value  # input registers and the like read back as outputs
        for group in ("standard", "configurable", "tool"):
            mask = inputs.get(f"{group}_digital_output_mask")
            if mask:
                self._set_digital(group, mask, inputs.get(f"{group}_digital_output", 0))
        if inputs.get("speed_slider_mask") and "speed_slider_fraction" in inputs:
            values["target_speed_fraction"] = float(inputs["speed_slider_fraction"])
        mask = inputs.get("standard_analog_output_mask")
        if mask:
            types = inputs.get("standard_analog_output_type", 0)
            io_types = values.get("analog_io_types", 0)
            for i, select in enumerate(_ANALOG_OUT_SELECT):
                if mask & select:
                    if f"standard_analog_output_{i}" in inputs:
                        values[f"standard_analog_output{i}"] = float(inputs[f"standard_analog_output_{i}"])
                    voltage = _ANALOG_OUT_VOLTAGE[i]
                    io_types = (io_types | voltage) if types & select else (io_types & ~voltage)
            values["analog_io_types"] = int(io_types)

    def _set_digital(self, group: str, mask: int, bits: int) -> None:
        shift = _SHIFT[group]
        current = self.values.get("actual_digital_output_bits", 0)
        updated = (current & ~(mask << shift)) | ((bits & mask) << shift)
        self.values["actual_digital_output_bits"] = updated
        if group == "configurable" and "actual_configurable_digital_output_bits" in self.values:
            self.values["actual_configurable_digital_output_bits"] = updated >> shift & 0xFF
