"""A Robot State message shaped like a UR5e's: 13 sub-packages, about 1.4 kB.

Built from the generated models (so it follows spec/primary), shared by the
benchmark and the tests.
"""

from __future__ import annotations

from rtde_spec._generated import primary_models as g
from rtde_spec.primary.base import RobotStateMessage
from rtde_spec.primary.codec import encode_message


def ur5e_robot_state() -> RobotStateMessage:
    joint = g.JointState(
        q_actual=0.1,
        q_target=0.1,
        qd_actual=0.0,
        i_actual=0.25,
        v_actual=47.5,
        t_motor=31.0,
        reserved=0.0,
        joint_mode=253,
    )
    return RobotStateMessage(
        sub_packages=[
            g.RobotModeData(
                timestamp=123456789,
                is_real_robot_connected=True,
                is_real_robot_enabled=True,
                is_robot_power_on=True,
                is_emergency_stopped=False,
                is_protective_stopped=False,
                is_program_running=True,
                is_program_paused=False,
                robot_mode=7,
                control_mode=0,
                target_speed_fraction=1.0,
                speed_scaling=1.0,
                target_speed_fraction_limit=1.0,
                reserved=0,
            ),
            g.JointData(joints=(joint,) * 6),
            g.CartesianInfo(
                x=0.1,
                y=-0.4,
                z=0.3,
                rx=3.14,
                ry=0.0,
                rz=0.0,
                tcp_offset_x=0.0,
                tcp_offset_y=0.0,
                tcp_offset_z=0.1,
                tcp_offset_rx=0.0,
                tcp_offset_ry=0.0,
                tcp_offset_rz=0.0,
            ),
            g.KinematicsInfo(
                checksum=(1, 2, 3, 4, 5, 6),
                dh_theta=(0.0,) * 6,
                dh_a=(0.0, -0.425, -0.3922, 0.0, 0.0, 0.0),
                dh_d=(0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996),
                dh_alpha=(1.57, 0.0, 0.0, 1.57, -1.57, 0.0),
                calibration_status=0,
            ),
            g.ConfigurationData(
                joint_limits=(g.JointLimits(joint_min_limit=-6.28, joint_max_limit=6.28),) * 6,
                joint_motion_limits=(g.JointMotionLimits(joint_max_speed=3.14, joint_max_acceleration=40.0),)
                * 6,
                v_joint_default=1.05,
                a_joint_default=1.4,
                v_tool_default=0.25,
                a_tool_default=1.2,
                eq_radius=0.2,
                dh_a=(0.0,) * 6,
                dh_d=(0.0,) * 6,
                dh_alpha=(0.0,) * 6,
                dh_theta=(0.0,) * 6,
                masterboard_version=1,
                reserved=0,
                robot_type=1,
                robot_sub_type=0,
            ),
            g.MasterboardData(
                digital_input_bits=0,
                digital_output_bits=5,
                analog_input_range0=0,
                analog_input_range1=0,
                analog_input0=0.0,
                analog_input1=0.0,
                analog_output_domain0=0,
                analog_output_domain1=0,
                analog_output0=0.0,
                analog_output1=0.0,
                masterboard_temperature=35.0,
                robot_voltage_48v=48.0,
                robot_current=0.75,
                master_io_current=0.0625,
                safety_mode=1,
                in_reduced_mode=False,
                immi_interface_installed=False,
                immi=None,
                reserved=0,
                operational_mode_selector_input=0,
                three_position_enabling_device_input=False,
                reserved_2=0,
            ),
            g.ToolData(
                analog_input_range0=0,
                analog_input_range1=0,
                analog_input0=0.0,
                analog_input1=0.0,
                tool_voltage_48v=24.0,
                tool_output_voltage=24,
                tool_current=0.125,
                tool_temperature=33.0,
                tool_mode=253,
            ),
            g.ForceModeData(fx=0.0, fy=0.0, fz=0.0, frx=0.0, fry=0.0, frz=0.0, robot_dexterity=0.9),
            g.AdditionalInfo(
                tp_button_state=0, is_manual_freedrive_allowed=True, is_freedrive_io_pressed=False, tp_type=1
            ),
            g.SafetyData(data=bytes(range(64))),
            g.ToolCommInfo(
                tool_communication_is_enabled=False,
                baud_rate=115200,
                parity=0,
                stop_bits=1,
                rx_idle_chars=1.5,
                tx_idle_chars=3.5,
            ),
            g.ToolModeInfo(output_mode=0, digital_output_mode_pin0=1, digital_output_mode_pin1=1),
            g.CumulativeRuntimeData(robot_energy_consumed_wh=12.5, robot_braking_energy_dissipated_wh=0.5),
        ]
    )


def ur5e_robot_state_bytes() -> bytes:
    return encode_message(ur5e_robot_state())
