"""The Robot State message a controller of one version sends, built from the spec and the model.

Which sub-packages go out, and when, follows the interface document: every message
carries the periodic ones; Configuration Data goes once after a client connects and
Kinematics Info with its Calibration Data then too (and again when the arm leaves
initialisation, i.e. is powered on); Cumulative Runtime Data once a second. The
e-Series order and sizes are URSim's: the first Robot State of a URSim 5.8 UR5e (the
capture in UR's C++ client library, Universal_Robots_Client_Library
tests/test_primary_parser.cpp) has sub-packages 0,1,4,5,9,3,2,6,7,8,10,11,12 in 1,386
bytes, Calibration Data a 48-byte body and Safety Data a 38-byte one (both "used by UR
software only": sent as zeros of their real size). A sub-package or field the spec says
a version does not have (`since`) is left out, so a CB3 controller sends its shorter
layouts. Kinematics Info reports a calibrated arm (calibration status 2, linearised,
what UR's calibration check wants); an uncalibrated one (a scenario's `calibrated:
false`) reports 0 and all-ones checksums, as URSim does. Values come from the same
controller model the RTDE port reads.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable, Mapping
from functools import cache
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.enums import (
    AnalogIoTypes,
    JointMode,
    ProgramState,
    RobotMode,
    RobotType,
    SafetyMode,
    TeachPendantType,
)
from rtde_spec.emulator.urscript.builtins_modes import control_mode
from rtde_spec.metamodel.arms import ArmModel, arm_model
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.versions import Version
from rtde_spec.primary import models as pm
from rtde_spec.primary.codec import decode_message, encode_message
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel

# sub-packages in the order a controller sends them, per product line (names from the spec)
ORDER = {
    "cb3": [
        "robot_mode_data", "joint_data", "cartesian_info", "kinematics_info", "calibration_data",
        "configuration_data", "masterboard_data", "tool_data", "force_mode_data", "additional_info",
    ],  # calibration data on CB3 too: UR's 2015 workbook lists it, 53 bytes (DataStreamFromURController)
    "e-series": [
        "robot_mode_data", "joint_data", "cartesian_info", "kinematics_info", "calibration_data",
        "masterboard_data", "tool_data", "configuration_data", "force_mode_data", "additional_info",
        "safety_data", "tool_comm_info", "tool_mode_info", "cumulative_runtime_data",
    ],
}  # fmt: skip
ORDER["polyscope-x"] = ORDER["e-series"]
ON_CONNECT = {"configuration_data", "kinematics_info", "calibration_data"}  # see the docstring
WITH_KINEMATICS = {"kinematics_info", "calibration_data"}  # again when the arm leaves initialisation
PER_SECOND = {"cumulative_runtime_data"}
SAFETY_DATA_BYTES = 38  # URSim 5.8's Safety Data body (43 bytes with its header)
CALIBRATION_DATA_BYTES = 48  # URSim 5.8's Calibration Data body (53 bytes with its header)
CALIBRATED, UNCALIBRATED = 2, 0  # calibration_status: 2 is "linearised", what UR's calibration check wants
EMERGENCY = {
    SafetyMode.ROBOT_EMERGENCY_STOP,
    SafetyMode.SYSTEM_EMERGENCY_STOP,
    SafetyMode.IMMI_EMERGENCY_STOP,
}
JOINT_ACCELERATION = 15.0  # rad/s², the configuration's joint acceleration limit (no data sheet gives one)
DEFAULTS = {"v_joint_default": 1.05, "a_joint_default": 1.4, "v_tool_default": 0.25, "a_tool_default": 1.2}


def arm_parameters(model: ControllerModel) -> ArmModel:
    """The arm the model moves (its DH rows and limits), else the product line's usual arm.

    The hook the kinematics sub-package and Configuration Data read.
    """
    found = getattr(getattr(model, "arm", None), "model", None)
    if isinstance(found, ArmModel):
        return found
    return arm_model("UR5" if model.line.id == "cb3" else "UR5e")


def robot_type(arm: ArmModel) -> tuple[int, int]:
    """(robotType, robotSubType): the arm's family by name (UR7e is a UR5e, UR12e a UR10e), and
    its series (spec/arms/models.yaml)."""
    family = {"UR7E": "UR5", "UR12E": "UR10"}.get(arm.name.upper(), arm.name.upper().removesuffix("E"))
    kind = int(RobotType[family]) if family in RobotType.__members__ else int(RobotType.UNDEFINED)
    return kind, arm.robot_sub_type


@cache
def _internal_part(kind: int, size: int) -> PrimaryPart:
    body = struct.pack(">IB", 5 + size, kind) + bytes(size)
    state = decode_message(struct.pack(">IB", 5 + len(body), 16) + body)
    part = state.sub_packages[0]  # type: ignore[union-attr]
    assert isinstance(part, PrimaryPart)
    return part


def _internal(kind: int, size: int) -> dict[str, Any]:
    """A sub-package of `size` zero bytes (URSim's size) as the spec's fields read them: Safety
    Data's one `data` field, Calibration Data's six doubles; whatever fields the spec gives it,
    the bytes sent stay the ones URSim sends."""
    part = _internal_part(kind, size)
    return {name: getattr(part, name) for name in type(part).model_fields if name not in ("extra", "missing")}


def available(since: Mapping[str, str] | None, version: Version, catalogue: Catalogue) -> bool:
    """Whether a member or field with this `since` is sent by `version` (lines inherit as catalogued)."""
    if since is None:
        return True
    line = catalogue.line_of(version)
    if line.id in since:
        return version >= Version.parse(since[line.id])
    return line.inherits is not None and line.inherits in since


class RobotStateBuilder:
    """Robot State bytes for one controller model: `build(first=...)` per 100 ms."""

    def __init__(self, model: ControllerModel) -> None:
        self.model = model
        catalogue = model.catalogue
        family = next(f for f in catalogue.spec.primary.families if f.layout == "subpackages")
        members = {m.name: m for m in family.members}
        self.classes: dict[str, type[PrimaryPart]] = {}
        self.absent: dict[str, tuple[str, ...]] = {}  # fields the version does not send
        for name in ORDER[model.line.id]:
            member = members[name]
            if not available(member.since, model.version, catalogue):
                continue
            self.classes[name] = next(c for c in pm.__dict__.values() if getattr(c, "NAME", None) == name)
            self.absent[name] = tuple(
                f.name for f in member.fields if not available(f.since, model.version, catalogue)
            )
        self.sent = 0
        self._values: dict[str, Callable[[], dict[str, Any]]] = {
            "robot_mode_data": self._robot_mode,
            "joint_data": self._joints,
            "cartesian_info": self._cartesian,
            "kinematics_info": self._kinematics,
            "configuration_data": self._configuration,
            "masterboard_data": self._masterboard,
            "tool_data": self._tool,
            "force_mode_data": lambda: (
                dict.fromkeys(("fx", "fy", "fz", "frx", "fry", "frz"), 0.0) | {"robot_dexterity": 1.0}
            ),
            "additional_info": lambda: {
                "tp_button_state": 0,
                "is_manual_freedrive_allowed": False,
                "is_freedrive_io_pressed": False,
                "tp_type": int(TeachPendantType.STANDARD),
            },
            "calibration_data": lambda: _internal(9, CALIBRATION_DATA_BYTES),
            "safety_data": lambda: _internal(10, SAFETY_DATA_BYTES),
            "tool_comm_info": lambda: dict(self.model.tool_communication),  # set_tool_communication
            "tool_mode_info": self._tool_mode,
            "cumulative_runtime_data": lambda: {
                "robot_energy_consumed_wh": 0.0,
                "robot_braking_energy_dissipated_wh": 0.0,
            },
        }

    @property
    def names(self) -> list[str]:
        """The sub-packages this version sends, in order (the first message after connecting)."""
        return list(self.classes)

    def build(self, first: bool = False, kinematics: bool = False, per_second: bool = False) -> bytes:
        """One Robot State: `first` after a client connects (all of them), else the periodic ones."""
        parts = []
        for name, cls in self.classes.items():
            if name in ON_CONNECT and not (first or (kinematics and name in WITH_KINEMATICS)):
                continue
            if name in PER_SECOND and not (first or per_second):
                continue
            values = self._values[name]()
            for absent in self.absent[name]:
                values[absent] = None
            parts.append(cls.model_construct(**values, extra=b"", missing=()))
        return encode_message(RobotStateMessage.model_construct(sub_packages=parts))

    # --- the values -----------------------------------------------------------

    def micros(self) -> int:
        return int(self.model.time * 1_000_000)

    def _robot_mode(self) -> dict[str, Any]:
        values = self.model.values
        mode = int(values.get("robot_mode", RobotMode.RUNNING))
        safety = int(values.get("safety_mode", SafetyMode.NORMAL))
        runtime = int(values.get("runtime_state", ProgramState.STOPPED))
        return {
            "timestamp": self.micros(),
            "is_real_robot_connected": True,
            "is_real_robot_enabled": not self.model.simulated,
            "is_robot_power_on": mode >= RobotMode.POWER_ON,
            "is_emergency_stopped": safety in EMERGENCY,
            "is_protective_stopped": safety == SafetyMode.PROTECTIVE_STOP,
            "is_program_running": runtime == ProgramState.RUNNING,
            "is_program_paused": runtime == ProgramState.PAUSED,
            "robot_mode": mode,
            "control_mode": control_mode(self.model.program),
            "target_speed_fraction": float(values.get("target_speed_fraction", 1.0)),
            "speed_scaling": float(values.get("speed_scaling", 1.0)),
            "target_speed_fraction_limit": 1.0,
            "reserved": 0,
        }

    def _joints(self) -> dict[str, Any]:
        values = self.model.values
        six = (0.0,) * 6
        q, q_target = values.get("actual_q", six), values.get("target_q", six)
        qd, current = values.get("actual_qd", six), values.get("actual_current", six)
        voltage = values.get("actual_joint_voltage", (48.0,) * 6)
        temperature = values.get("joint_temperatures", (30.0,) * 6)
        modes = values.get("joint_mode", (int(JointMode.RUNNING),) * 6)
        joints = tuple(
            pm.JointState.model_construct(
                q_actual=q[i], q_target=q_target[i], qd_actual=qd[i], i_actual=current[i],
                v_actual=voltage[i], t_motor=temperature[i], reserved=0.0, joint_mode=modes[i],
            )
            for i in range(6)
        )  # fmt: skip
        return {"joints": joints}

    def _cartesian(self) -> dict[str, Any]:
        values = self.model.values
        pose = values.get("actual_TCP_pose", (0.0,) * 6)
        offset = values.get("tcp_offset", (0.0,) * 6)
        keys = ("x", "y", "z", "rx", "ry", "rz")
        return dict(zip(keys, pose, strict=True)) | {
            f"tcp_offset_{k}": v for k, v in zip(keys, offset, strict=True)
        }

    def _kinematics(self) -> dict[str, Any]:
        dh = arm_parameters(self.model).dh
        calibrated = bool(getattr(self.model, "calibrated", True))
        rows = zip(dh.a, dh.d, dh.alpha, strict=True)
        checksum = (
            tuple(zlib.crc32(struct.pack(">4d", 0.0, *row)) for row in rows)  # per joint, of its DH row
            if calibrated
            else (0xFFFFFFFF,) * 6
        )
        return {
            "checksum": checksum,
            "dh_theta": (0.0,) * 6,
            "dh_a": tuple(dh.a),
            "dh_d": tuple(dh.d),
            "dh_alpha": tuple(dh.alpha),
            "calibration_status": CALIBRATED if calibrated else UNCALIBRATED,
        }

    def _configuration(self) -> dict[str, Any]:
        arm = arm_parameters(self.model)
        kind, sub = robot_type(arm)
        return {
            "joint_limits": tuple(
                pm.JointLimits.model_construct(joint_min_limit=low, joint_max_limit=high)
                for low, high in arm.joint_limits
            ),
            "joint_motion_limits": tuple(
                pm.JointMotionLimits.model_construct(
                    joint_max_speed=v, joint_max_acceleration=JOINT_ACCELERATION
                )
                for v in arm.max_joint_speed
            ),
            **DEFAULTS,
            "eq_radius": arm.reach_m,
            "dh_a": tuple(arm.dh.a),
            "dh_d": tuple(arm.dh.d),
            "dh_alpha": tuple(arm.dh.alpha),
            "dh_theta": (0.0,) * 6,
            "masterboard_version": 3,
            "reserved": arm.controller_box_type or 0,  # the controller box type (spec/arms/models.yaml)
            "robot_type": kind,
            "robot_sub_type": sub,
        }

    def _masterboard(self) -> dict[str, Any]:
        """I/O, supply and safety mode as the RTDE outputs have them.

        The document gives no encoding of the analog ranges and domains; the emulator
        sends 1 for voltage and 0 for current, as the bits of RTDE's analog_io_types.
        """
        values = self.model.values
        types = int(values.get("analog_io_types", 0))
        return {
            "digital_input_bits": int(values.get("actual_digital_input_bits", 0)) & 0xFFFF,
            "digital_output_bits": int(values.get("actual_digital_output_bits", 0)) & 0xFFFF,
            "analog_input_range0": int(bool(types & AnalogIoTypes.ANALOG_INPUT_0_VOLTAGE)),
            "analog_input_range1": int(bool(types & AnalogIoTypes.ANALOG_INPUT_1_VOLTAGE)),
            "analog_input0": values.get("standard_analog_input0", 0.0),
            "analog_input1": values.get("standard_analog_input1", 0.0),
            "analog_output_domain0": int(bool(types & AnalogIoTypes.ANALOG_OUTPUT_0_VOLTAGE)),
            "analog_output_domain1": int(bool(types & AnalogIoTypes.ANALOG_OUTPUT_1_VOLTAGE)),
            "analog_output0": values.get("standard_analog_output0", 0.0),
            "analog_output1": values.get("standard_analog_output1", 0.0),
            "masterboard_temperature": 35.0,
            "robot_voltage_48v": values.get("actual_robot_voltage", 48.0) or 48.0,
            "robot_current": values.get("actual_robot_current", 0.0),
            "master_io_current": values.get("io_current", 0.0),
            "safety_mode": int(values.get("safety_mode", SafetyMode.NORMAL)),
            "in_reduced_mode": int(values.get("safety_mode", 0)) == SafetyMode.REDUCED,
            "immi_interface_installed": False,
            "immi": None,
            "reserved": 0,
            "operational_mode_selector_input": 0,
            "three_position_enabling_device_input": False,
            "reserved_2": 0,
        }

    def _tool(self) -> dict[str, Any]:
        values = self.model.values
        types = int(values.get("tool_analog_input_types", 0))
        return {
            "analog_input_range0": types & 1,
            "analog_input_range1": types >> 1 & 1,
            "analog_input0": values.get("tool_analog_input0", 0.0),
            "analog_input1": values.get("tool_analog_input1", 0.0),
            "tool_voltage_48v": 48.0,
            "tool_output_voltage": int(values.get("tool_output_voltage", 0)),
            "tool_current": values.get("tool_output_current", 0.0),
            "tool_temperature": values.get("tool_temperature", 30.0) or 30.0,
            "tool_mode": int(values.get("tool_mode", 0)) or int(JointMode.RUNNING),
        }

    def _tool_mode(self) -> dict[str, Any]:
        values = self.model.values
        return {
            "output_mode": int(values.get("tool_output_mode", 0)),
            "digital_output_mode_pin0": int(values.get("tool_digital_output0_mode", 0)),
            "digital_output_mode_pin1": int(values.get("tool_digital_output1_mode", 0)),
        }
