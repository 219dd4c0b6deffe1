"""The emulator's primary and secondary ports: the Version message, then Robot State at 10 Hz
(robot mode, joints, cartesian info, masterboard).

The Robot State is built from the same model the RTDE port reads, so a client sees
the same joint positions and modes on both. What a client sends is cut into
scripts (a line, or a `def ... end` program; script_framer.py), the last few kept, their
I/O calls run (`script.py`); read-only ports drop what they get, as a controller does.
Each client is held to the port's limits (guard.py).
"""

from __future__ import annotations

import logging
from collections import deque
from typing import TYPE_CHECKING

from rtde_spec._generated.enums import (
    AnalogIoTypes,
    ControlMode,
    MessageSource,
    RobotMessageType,
    RobotMode,
    SafetyMode,
)
from rtde_spec.emulator.guard import GuardedConnection, Port
from rtde_spec.emulator.script import run_script
from rtde_spec.emulator.script_framer import ScriptFramer
from rtde_spec.errors import ProtocolError
from rtde_spec.primary import models as pm
from rtde_spec.primary.base import RobotStateMessage
from rtde_spec.primary.codec import encode_message

if TYPE_CHECKING:
    from rtde_spec.emulator.model import ControllerModel

log = logging.getLogger("rtde_spec.emulator")
PROJECT = "URControl"
BUILD_DATE = "emulated by rtde_spec"
KEEP_SCRIPTS = 64  # the last scripts received, for tests and `watch` to look at
CARTESIAN = [n for n in pm.CartesianInfo.model_fields if n not in ("extra", "missing")]


class PrimaryHub:
    """Connections of the primary/secondary ports and the scripts they received."""

    def __init__(self, model: ControllerModel) -> None:
        self.model = model
        self.connections: set[PrimaryConnection] = set()
        self.scripts: deque[tuple[int, str]] = deque(maxlen=KEEP_SCRIPTS)  # (port, script text)

    def run(self, port: int, text: str) -> None:
        """A whole script from a client: kept (the last few), its I/O calls run."""
        self.scripts.append((port, text))
        applied = run_script(self.model, text)
        log.info("URScript on port %d: %s (%d I/O calls run)", port, text.strip()[:80], len(applied))

    def version_message(self) -> bytes:
        v = self.model.version
        return encode_message(
            pm.VersionMessage(
                timestamp=self._micros(),
                source=int(MessageSource.ROBOTINTERFACE),
                robot_message_type=int(RobotMessageType.VERSION),
                project_name=PROJECT,
                major_version=v.major,
                minor_version=v.minor,
                bugfix_version=v.bugfix,
                build_number=v.build or 0,
                build_date=BUILD_DATE,
            )
        )

    def robot_state(self) -> bytes:
        values = self.model.values
        q, q_target = values.get("actual_q", (0.0,) * 6), values.get("target_q", (0.0,) * 6)
        qd = values.get("actual_qd", (0.0,) * 6)
        current = values.get("actual_current", (0.0,) * 6)
        voltage = values.get("actual_joint_voltage", (48.0,) * 6)
        temperature = values.get("joint_temperatures", (30.0,) * 6)
        modes = values.get("joint_mode", (0,) * 6)
        joints = tuple(
            pm.JointState(
                q_actual=q[i],
                q_target=q_target[i],
                qd_actual=qd[i],
                i_actual=current[i],
                v_actual=voltage[i],
                t_motor=temperature[i],
                reserved=0.0,
                joint_mode=modes[i],
            )
            for i in range(6)
        )
        mode = int(values.get("robot_mode", RobotMode.RUNNING))
        pose = values.get("actual_TCP_pose", (0.0,) * 6)
        offset = values.get("tcp_offset", (0.0,) * 6)
        message = RobotStateMessage(
            sub_packages=[
                pm.RobotModeData(
                    timestamp=self._micros(),
                    is_real_robot_connected=True,
                    is_real_robot_enabled=True,
                    is_robot_power_on=mode >= RobotMode.POWER_ON,
                    is_emergency_stopped=False,
                    is_protective_stopped=False,
                    is_program_running=False,
                    is_program_paused=False,
                    robot_mode=mode,
                    control_mode=int(ControlMode.POSITION),
                    target_speed_fraction=values.get("target_speed_fraction", 1.0),
                    speed_scaling=values.get("speed_scaling", 1.0),
                    target_speed_fraction_limit=1.0,
                    reserved=0,
                ),
                pm.JointData(joints=joints),
                pm.CartesianInfo(**dict(zip(CARTESIAN, (*pose, *offset), strict=True))),
                self._masterboard(),
            ]
        )
        return encode_message(message)

    def _masterboard(self) -> pm.MasterboardData:
        """I/O, supply and safety mode as the RTDE outputs have them.

        The document gives no encoding of the analog ranges and domains; the emulator
        sends 1 for voltage and 0 for current, as the bits of RTDE's analog_io_types.
        """
        values = self.model.values
        types = int(values.get("analog_io_types", 0))
        return pm.MasterboardData(
            digital_input_bits=int(values.get("actual_digital_input_bits", 0)) & 0xFFFF,
            digital_output_bits=int(values.get("actual_digital_output_bits", 0)) & 0xFFFF,
            analog_input_range0=int(bool(types & AnalogIoTypes.ANALOG_INPUT_0_VOLTAGE)),
            analog_input_range1=int(bool(types & AnalogIoTypes.ANALOG_INPUT_1_VOLTAGE)),
            analog_input0=values.get("standard_analog_input0", 0.0),
            analog_input1=values.get("standard_analog_input1", 0.0),
            analog_output_domain0=int(bool(types & AnalogIoTypes.ANALOG_OUTPUT_0_VOLTAGE)),
            analog_output_domain1=int(bool(types & AnalogIoTypes.ANALOG_OUTPUT_1_VOLTAGE)),
            analog_output0=values.get("standard_analog_output0", 0.0),
            analog_output1=values.get("standard_analog_output1", 0.0),
            masterboard_temperature=35.0,
            robot_voltage_48v=values.get("actual_robot_voltage", 48.0) or 48.0,
            robot_current=values.get("actual_robot_current", 0.0),
            master_io_current=values.get("io_current", 0.0),
            safety_mode=int(values.get("safety_mode", SafetyMode.NORMAL)),
            in_reduced_mode=False,
            immi_interface_installed=False,
            immi=None,
            reserved=0,
            operational_mode_selector_input=0,
            three_position_enabling_device_input=False,
            reserved_2=0,
        )

    def broadcast_state(self) -> None:
        if self.connections:
            data = self.robot_state()
            for conn in list(self.connections):
                conn.send(data)

    def _micros(self) -> int:
        return int(self.model.time * 1_000_000)


class PrimaryConnection(GuardedConnection):
    """One client of a primary/secondary port: the Version message, Robot State, its scripts run."""

    def __init__(self, hub: PrimaryHub, port: Port, number: int, read_only: bool) -> None:
        super().__init__(port)
        self.hub, self.number, self.read_only = hub, number, read_only
        self.framer = ScriptFramer()

    def opened(self) -> None:
        self.hub.connections.add(self)
        self.write(self.hub.version_message())

    def closed(self) -> None:
        self.hub.connections.discard(self)

    def data_received(self, data: bytes) -> None:
        if self.read_only or self.dropped:
            return  # a read-only port ignores what clients send
        try:
            scripts = self.framer.feed(data)
        except ProtocolError as exc:
            self.drop(f"sent {exc}")
            return
        if self.received(self.framer.pending, len(scripts)):
            for text in scripts:
                self.hub.run(self.number, text)

    def send(self, data: bytes) -> None:
        self.write(data)
