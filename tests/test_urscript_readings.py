"""The Script Directory's readings a program asks for (force, temperatures, the tool's current and
accelerometer) are the RTDE outputs that carry them; flags outlive the program that set them."""

from __future__ import annotations

from .test_urscript_polyscope_programs import faults, start, steps, texts


def test_readings_are_what_rtde_clients_see() -> None:
    model, _ = start("def p():\n  sleep(1)\nend\n")
    model.stop_program()
    model.values["actual_TCP_force"] = (3.0, -4.0, 12.0, 0.5, 0.5, 0.5)
    model.values["joint_temperatures"] = (31.0, 32.0, 33.0, 34.0, 35.0, 36.5)
    model.values["tool_temperature"] = 40.25
    model.values["tool_output_current"] = 150.0  # mA
    model.values["actual_tool_accelerometer"] = (0.0, 0.0, 9.81)
    model.run_script(
        "def p():\n"
        "  textmsg(force(), get_joint_temp(5))\n"
        "  textmsg(get_tool_temp(), get_tool_current())\n"
        "  textmsg(get_tool_accelerometer_reading())\n"
        "  x = get_joint_temp(6)\n"
        "end\n"
    )
    events = model.drain_events() + steps(model, 5)
    assert texts(events) == ["1336.5", "40.250.15", "[0, 0, 9.81]"]
    assert faults(events) == [("get_joint_temp: j must be an int of 0 to 5, not 6", 5)]


def test_flags_are_kept_between_program_runs() -> None:
    model, events = start(
        "def p():\n  textmsg(get_flag(31))\n  set_flag(31, True)\n  set_flag(0, True)\nend\n"
    )
    events += steps(model, 5)
    model.run_script(
        "def q():\n  textmsg(get_flag(31), get_flag(0), get_flag(1))\n  set_flag(32, True)\nend\n"
    )
    events += model.drain_events() + steps(model, 5)
    assert texts(events) == ["False", "TrueTrueFalse"]
    assert faults(events) == [("set_flag: n must be an int of 0 to 31, not 32", 3)]


def test_gravity_and_base_acceleration_read_back_what_the_program_set() -> None:
    model, events = start(
        "def p():\n"
        "  textmsg(get_gravity(), get_base_acceleration())\n"
        "  set_gravity([0, 9.82, 0])\n"
        "  set_base_acceleration([0.1, 0, 0])\n"
        "  high_holding_torque_disable()\n"
        "  textmsg(get_gravity(), get_base_acceleration())\n"
        "  set_gravity([0, 9.82])\n"
        "end\n"
    )
    events += steps(model, 5)
    assert texts(events) == ["[0, 0, 9.82][0, 0, 0]", "[0, 9.82, 0][0.1, 0, 0]"]
    assert faults(events) == [("set_gravity: d must be three numbers", 7)]


def test_the_modbus_calls_that_steer_polling_check_their_signal() -> None:
    model, events = start(
        "def p():\n"
        '  modbus_add_signal("0.0.0.0", 255, 0, 0, "din")\n'
        '  modbus_set_digital_input_action("din", "freedrive")\n'
        '  modbus_request_update_signal_value("din")\n'
        '  modbus_reset_connection("0.0.0.0")\n'
        '  modbus_reset_connection("0.0.0.0", False)\n'
        '  textmsg("ok")\n'
        '  modbus_set_digital_input_action("din", "pause")\n'
        "end\n"
    )
    events += steps(model, 5)
    assert texts(events) == ["ok"]
    assert faults(events) == [
        ("modbus_set_digital_input_action: 'din' must be a digital input and action \"default\" or "
         "\"freedrive\", not 'pause'", 8)
    ]  # fmt: skip
    assert model.program is None
