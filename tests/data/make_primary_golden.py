"""How tests/data/primary_golden.yaml was made: each message packed with struct
formats typed from the primary/secondary interface document, independent of the
spec and the codec. Run once; the YAML is what the tests read.

    python tests/data/make_primary_golden.py > tests/data/primary_golden.yaml
"""

from __future__ import annotations

import struct

import yaml


def msg(mtype: int, body: bytes) -> bytes:
    return struct.pack(">IB", 5 + len(body), mtype) + body


def sub(stype: int, body: bytes) -> bytes:
    return struct.pack(">IB", 5 + len(body), stype) + body


def state(stype: int, body: bytes) -> bytes:
    return msg(16, sub(stype, body))


def robot_message(rtype: int, body: bytes, ts: int = 1000, source: int = -2) -> bytes:
    return msg(20, struct.pack(">QbB", ts, source, rtype) + body)


def program_state(ptype: int, body: bytes, ts: int = 2000) -> bytes:
    return msg(25, struct.pack(">QB", ts, ptype) + body)


def s16(text: str) -> bytes:
    data = text.encode()
    return struct.pack(">H", len(data)) + data


def s8(text: str) -> bytes:
    data = text.encode()
    return struct.pack(">B", len(data)) + data


joint = dict(
    q_actual=0.5,
    q_target=0.25,
    qd_actual=-1.0,
    i_actual=1.5,
    v_actual=48.0,
    t_motor=32.5,
    reserved=0.0,
    joint_mode=253,
)
CASES = [
    (
        "robot_mode_data",
        state(
            0,
            struct.pack(
                ">Q7?BBdddB", 123456, True, True, True, False, False, True, False, 7, 0, 1.0, 0.5, 1.0, 0
            ),
        ),
        dict(
            timestamp=123456,
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
            speed_scaling=0.5,
            target_speed_fraction_limit=1.0,
            reserved=0,
        ),
    ),
    (
        "joint_data",
        state(1, struct.pack(">dddffffB", 0.5, 0.25, -1.0, 1.5, 48.0, 32.5, 0.0, 253) * 6),
        dict(joints=[joint] * 6),
    ),
    (
        "tool_data",
        state(2, struct.pack(">BBddfBffB", 1, 0, 0.5, 2.0, 24.0, 24, 0.125, 30.0, 253)),
        dict(
            analog_input_range0=1,
            analog_input_range1=0,
            analog_input0=0.5,
            analog_input1=2.0,
            tool_voltage_48v=24.0,
            tool_output_voltage=24,
            tool_current=0.125,
            tool_temperature=30.0,
            tool_mode=253,
        ),
    ),
    (
        "masterboard_data",
        state(
            3,
            struct.pack(
                ">IIBBddBBddffffB??IB?B",
                3,
                5,
                0,
                1,
                1.0,
                2.0,
                0,
                1,
                3.0,
                4.0,
                35.0,
                48.0,
                0.75,
                0.0625,
                1,
                False,
                False,
                0,
                1,
                True,
                0,
            ),
        ),
        dict(
            digital_input_bits=3,
            digital_output_bits=5,
            analog_input_range0=0,
            analog_input_range1=1,
            analog_input0=1.0,
            analog_input1=2.0,
            analog_output_domain0=0,
            analog_output_domain1=1,
            analog_output0=3.0,
            analog_output1=4.0,
            masterboard_temperature=35.0,
            robot_voltage_48v=48.0,
            robot_current=0.75,
            master_io_current=0.0625,
            safety_mode=1,
            in_reduced_mode=False,
            immi_interface_installed=False,
            immi=None,
            reserved=0,
            operational_mode_selector_input=1,
            three_position_enabling_device_input=True,
            reserved_2=0,
        ),
    ),
    (
        "masterboard_data",
        state(
            3,
            struct.pack(
                ">IIBBddBBddffffB??IIffIB?B",
                3,
                5,
                0,
                1,
                1.0,
                2.0,
                0,
                1,
                3.0,
                4.0,
                35.0,
                48.0,
                0.75,
                0.0625,
                1,
                False,
                True,
                7,
                9,
                24.0,
                0.5,
                0,
                1,
                True,
                0,
            ),
        ),
        dict(
            digital_input_bits=3,
            digital_output_bits=5,
            analog_input_range0=0,
            analog_input_range1=1,
            analog_input0=1.0,
            analog_input1=2.0,
            analog_output_domain0=0,
            analog_output_domain1=1,
            analog_output0=3.0,
            analog_output1=4.0,
            masterboard_temperature=35.0,
            robot_voltage_48v=48.0,
            robot_current=0.75,
            master_io_current=0.0625,
            safety_mode=1,
            in_reduced_mode=False,
            immi_interface_installed=True,
            immi=dict(immi_input_bits=7, immi_output_bits=9, immi_voltage_24v=24.0, immi_current=0.5),
            reserved=0,
            operational_mode_selector_input=1,
            three_position_enabling_device_input=True,
            reserved_2=0,
        ),
    ),
    (
        "cartesian_info",
        state(4, struct.pack(">12d", *[float(i) for i in range(12)])),
        dict(
            zip(
                [
                    "x",
                    "y",
                    "z",
                    "rx",
                    "ry",
                    "rz",
                    "tcp_offset_x",
                    "tcp_offset_y",
                    "tcp_offset_z",
                    "tcp_offset_rx",
                    "tcp_offset_ry",
                    "tcp_offset_rz",
                ],
                [float(i) for i in range(12)],
                strict=True,
            )
        ),
    ),
    (
        "kinematics_info",
        state(5, struct.pack(">6I24dI", *range(1, 7), *[i / 4 for i in range(24)], 1)),
        dict(
            checksum=list(range(1, 7)),
            dh_theta=[i / 4 for i in range(6)],
            dh_a=[i / 4 for i in range(6, 12)],
            dh_d=[i / 4 for i in range(12, 18)],
            dh_alpha=[i / 4 for i in range(18, 24)],
            calibration_status=1,
        ),
    ),
    (
        "configuration_data",
        state(
            6,
            struct.pack(
                ">12d12d5d24d4i",
                *[-6.0, 6.0] * 6,
                *[3.0, 40.0] * 6,
                1.0,
                1.5,
                0.25,
                1.25,
                0.5,
                *[0.125] * 24,
                3,
                0,
                1,
                2,
            ),
        ),
        dict(
            joint_limits=[dict(joint_min_limit=-6.0, joint_max_limit=6.0)] * 6,
            joint_motion_limits=[dict(joint_max_speed=3.0, joint_max_acceleration=40.0)] * 6,
            v_joint_default=1.0,
            a_joint_default=1.5,
            v_tool_default=0.25,
            a_tool_default=1.25,
            eq_radius=0.5,
            dh_a=[0.125] * 6,
            dh_d=[0.125] * 6,
            dh_alpha=[0.125] * 6,
            dh_theta=[0.125] * 6,
            masterboard_version=3,
            reserved=0,
            robot_type=1,
            robot_sub_type=2,
        ),
    ),
    (
        "force_mode_data",
        state(7, struct.pack(">7d", 0, 0, 0, 0, 0, 0, 0.75)),
        dict(fx=0.0, fy=0.0, fz=0.0, frx=0.0, fry=0.0, frz=0.0, robot_dexterity=0.75),
    ),
    (
        "additional_info",
        state(8, struct.pack(">B??B", 0, True, False, 2)),
        dict(tp_button_state=0, is_manual_freedrive_allowed=True, is_freedrive_io_pressed=False, tp_type=2),
    ),
    (
        # the 5.9/5.10 document's six doubles (ClientInterfaces_Primary.pdf)
        "calibration_data",
        state(9, struct.pack(">6d", 0.5, -0.25, 1.0, 0.0, 2.0, -3.5)),
        dict(fx=0.5, fy=-0.25, fz=1.0, frx=0.0, fry=2.0, frz=-3.5),
    ),
    ("safety_data", state(10, bytes(range(16))), dict(data=bytes(range(16)).hex())),
    (
        "tool_comm_info",
        state(11, struct.pack(">?iiiff", True, 115200, 0, 1, 1.5, 3.5)),
        dict(
            tool_communication_is_enabled=True,
            baud_rate=115200,
            parity=0,
            stop_bits=1,
            rx_idle_chars=1.5,
            tx_idle_chars=3.5,
        ),
    ),
    (
        "tool_mode_info",
        state(12, struct.pack(">BBB", 1, 2, 3)),
        dict(output_mode=1, digital_output_mode_pin0=2, digital_output_mode_pin1=3),
    ),
    (
        "singularity_info",
        state(13, struct.pack(">BB", 1, 2)),
        dict(singularity_severity=1, singularity_type=2),
    ),
    ("payload_info", state(14, b"\x01\x02"), dict(data="0102")),
    ("internal_data", state(15, b""), dict(data="")),
    (
        "cumulative_runtime_data",
        state(16, struct.pack(">dd", 12.5, 0.25)),
        dict(robot_energy_consumed_wh=12.5, robot_braking_energy_dissipated_wh=0.25),
    ),
    (
        "text_message",
        robot_message(0, b"Hello"),
        dict(timestamp=1000, source=-2, robot_message_type=0, text_message="Hello"),
    ),
    (
        "version_message",
        robot_message(3, s8("URControl") + struct.pack(">BBii", 5, 15, 0, 1234) + b"01-01-2024"),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=3,
            project_name="URControl",
            major_version=5,
            minor_version=15,
            bugfix_version=0,
            build_number=1234,
            build_date="01-01-2024",
        ),
    ),
    (
        "safety_mode_message",
        robot_message(5, struct.pack(">iiBIf", 209, 3, 3, 3, 1.5), source=30),
        dict(
            timestamp=1000,
            source=30,
            robot_message_type=5,
            robot_message_code=209,
            robot_message_argument=3,
            safety_mode_type=3,
            report_data_type=3,
            report_data=1.5,
        ),
    ),
    (
        "robot_comm_message",
        robot_message(6, struct.pack(">IIiI", 100, 2, 2, 2) + struct.pack(">i", -7)),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=6,
            robot_message_code=100,
            robot_message_argument=2,
            robot_message_report_level=2,
            data_type=2,
            report_data=-7,
            report_text="",
        ),
    ),
    (
        # as UR's C++ client library reads it: a text after the 4-byte value
        "robot_comm_message",
        robot_message(6, struct.pack(">IIiI", 100, 2, 2, 2) + struct.pack(">i", -7) + b"Protective stop"),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=6,
            robot_message_code=100,
            robot_message_argument=2,
            robot_message_report_level=2,
            data_type=2,
            report_data=-7,
            report_text="Protective stop",
        ),
    ),
    (
        "robot_comm_message",
        robot_message(6, struct.pack(">IIiI", 100, 2, 4, 5) + s16("joint fault")),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=6,
            robot_message_code=100,
            robot_message_argument=2,
            robot_message_report_level=4,
            data_type=5,
            report_data="joint fault",
            report_text="",
        ),
    ),
    (
        "key_message",
        robot_message(7, struct.pack(">II", 1, 2) + s8("Title") + s16("Key text")),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=7,
            robot_message_code=1,
            robot_message_argument=2,
            robot_message_title="Title",
            key_text_message="Key text",
        ),
    ),
    (
        # as UR's C++ client library and real controllers send it: no length before the text
        "key_message",
        robot_message(7, struct.pack(">II", 1, 2) + s8("Title") + b"Key text without a length"),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=7,
            robot_message_code=1,
            robot_message_argument=2,
            robot_message_title="Title",
            key_text_message="Key text without a length",
        ),
        # encoding writes the document's form: the uint16 length before the text
        robot_message(7, struct.pack(">II", 1, 2) + s8("Title") + s16("Key text without a length")),
    ),
    (
        "request_value_message",
        robot_message(9, struct.pack(">II", 42, 1) + b"How many?"),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=9,
            request_id=42,
            requested_type=1,
            request_text_message="How many?",
        ),
    ),
    (
        "runtime_exception_message",
        robot_message(10, struct.pack(">II", 12, 4) + b"name 'x' is not defined"),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=10,
            script_line_number=12,
            script_column_number=4,
            runtime_exception_text_message="name 'x' is not defined",
        ),
    ),
    (
        "program_threads_message",
        robot_message(
            14, struct.pack(">i", 3) + s8("lbl") + s16("main") + struct.pack(">i", 7) + s8("") + s16("t2")
        ),
        dict(
            timestamp=1000,
            source=-2,
            robot_message_type=14,
            threads=[
                dict(label_id=3, label_name="lbl", thread_name="main"),
                dict(label_id=7, label_name="", thread_name="t2"),
            ],
        ),
    ),
    (
        "global_variables_setup_message",
        program_state(0, struct.pack(">H", 0) + b"var_1\nvar_2\n"),
        dict(timestamp=2000, robot_message_type=0, start_index=0, variable_names=["var_1", "var_2"]),
    ),
    # the document's example (BOOL true, STRING "aaaa"), with BOOL's code from its table (0x0d)
    (
        "global_variables_update_message",
        program_state(1, struct.pack(">H", 4) + bytes.fromhex("0d010a030004616161610a")),
        dict(
            timestamp=2000,
            robot_message_type=1,
            start_index=4,
            variable_values=[dict(type="BOOL", value=True), dict(type="CONST_STRING", value="aaaa")],
        ),
    ),
    (
        "global_variables_update_message",
        program_state(
            1,
            struct.pack(">H", 0)
            + b"\x0c"
            + struct.pack(">6f", 1, 2, 3, 0, 0, 0.5)
            + b"\n"
            + b"\x11"
            + struct.pack(">H", 2)
            + b"\x0f"
            + struct.pack(">i", -1)
            + b"\x00"
            + b"\n"
            + b"\x12"
            + struct.pack(">HH", 1, 2)
            + b"\x0e"
            + struct.pack(">f", 0.5)
            + b"\x10"
            + struct.pack(">f", 2.0)
            + b"\n"
            + b"\x04"
            + s16("x")
            + b"\n",
        ),
        dict(
            timestamp=2000,
            robot_message_type=1,
            start_index=0,
            variable_values=[
                dict(type="POSE", value=[1.0, 2.0, 3.0, 0.0, 0.0, 0.5]),
                dict(type="LIST", value=[dict(type="INT", value=-1), dict(type="NONE", value=None)]),
                dict(type="MATRIX", value=[[dict(type="NUM", value=0.5), dict(type="FLOAT", value=2.0)]]),
                dict(type="VAR_STRING", value="x"),
            ],
        ),
    ),
    ("modbus_info_message", msg(5, b"\x01\x02\x03"), dict(raw="010203")),
]


class _NoAliases(yaml.SafeDumper):
    def ignore_aliases(self, data: object) -> bool:
        return True


if __name__ == "__main__":
    print("# Generated by tests/data/make_primary_golden.py from struct formats typed from the document.")
    print(
        yaml.dump(
            [
                {"message": name, "hex": data.hex(), "fields": fields}
                | ({"encodes_as": rest[0].hex()} if rest else {})
                for name, data, fields, *rest in CASES
            ],
            sort_keys=False,
            width=120,
            Dumper=_NoAliases,
        )
    )
