"""The CB-era I/O calls older programs still send: python-urx's Robotiq gripper program (run on a
CB3 by Robotiq in 2017, python-urx PR #26) starts with set_analog_inputrange and
set_runstate_outputs([]), as CB-era PolyScope preambles did."""

from __future__ import annotations

import pytest

from .test_urscript_polyscope_programs import faults, start, steps, texts

URX_PREAMBLE = (
    "def gripper_action():\n"
    "  set_analog_inputrange(0, 0)\n"
    "  set_analog_inputrange(1, 2)\n"
    "  set_analog_inputrange(2, 2)\n"
    "  set_analog_inputrange(3, 0)\n"
    "  set_analog_outputdomain(0, 0)\n"
    "  set_analog_outputdomain(1, 0)\n"
    "  set_tool_voltage(0)\n"
    "  set_runstate_outputs([])\n"
    "  set_payload(1.1)\n"
    '  textmsg("ran")\n'
    "end\n"
)


def test_python_urx_s_preamble_runs_on_a_cb3_and_sets_the_input_ranges() -> None:
    model, events = start(URX_PREAMBLE, "3.15.8")
    events += steps(model, 10)
    assert faults(events) == [] and texts(events) == ["ran"]
    assert model.values["analog_io_types"] & 0b11 == 0b11  # the controller's inputs: 0-10 V
    assert model.values["tool_analog_input_types"] == 0b10  # tool input 0: 4-20 mA, 1: volts


def test_set_analog_inputrange_is_the_e_series_deprecated_call_too() -> None:
    model, events = start("def p():\n  set_analog_inputrange(2, 1)\n  textmsg(1)\nend\n", "5.15.0")
    events += steps(model, 5)
    assert faults(events) == [] and model.values["tool_analog_input_types"] & 0b1


def test_set_runstate_outputs_is_cb_era_only() -> None:
    _, events = start("def p():\n  set_runstate_outputs([])\nend\n", "5.15.0")
    assert faults(events) == [("compile_error_name_not_found:set_runstate_outputs:", 2)]


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ("set_analog_inputrange(0, 1)", "range must be one of 0, 2, not 1"),  # -5-5 V: no longer
        ("set_analog_inputrange(1, 3)", "range must be one of 0, 2, not 3"),
        ("set_analog_inputrange(2, 3)", "range must be one of 0, 1, 2, not 3"),
        ("set_analog_inputrange(4, 0)", "port must be one of 0, 1, 2, 3, not 4"),
        ('set_runstate_outputs("0")', "outputs must be a list of output numbers"),
    ],
)
def test_a_range_or_output_the_manual_rules_out_is_a_runtime_exception(line: str, problem: str) -> None:
    model, events = start(f"def p():\n  x = 1\n  {line}\nend\n", "3.15.8")
    events += steps(model, 3)
    ((text, at),) = faults(events)
    assert problem in text and at == 3, text
