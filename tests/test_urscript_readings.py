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
