"""The Script Directory's later Modbus functions UR's festo-cmmt-as example calls: a read-write
signal (function code 23), its error state, the time it has been invalid and its watchdog. No
device is polled, so no signal fails and the registers a device would give read 0."""

from __future__ import annotations

import pytest

from .test_urscript_control import faults, run, said

FESTO_LIKE = (
    "def prog():\n"
    '  modbus_add_rw_signal("0.0.0.0", 255, 100, 3, 0, 2, "servo", True)\n'
    '  modbus_set_signal_update_frequency("servo", 20)\n'
    '  modbus_set_signal_watchdog("servo", 10.5)\n'
    '  textmsg(modbus_get_error("servo"), modbus_get_error("servo", 2))\n'
    '  textmsg(modbus_get_time_since_signal_invalid("servo"))\n'
    '  modbus_set_output_register("servo", [1086, 7], False)\n'
    '  textmsg(modbus_get_signal_status("servo", False))\n'
    '  modbus_add_rw_signal("0.0.0.0", 255, 5, 1, 15, 1, "one")\n'
    '  modbus_set_output_register("one", 300)\n'
    '  textmsg(modbus_get_signal_status("one"))\n'
    "end\n"
)


def test_a_read_write_signal_is_written_reads_its_device_s_registers_and_has_no_error() -> None:
    _, events = run(FESTO_LIKE)
    assert not faults(events)
    assert said(events) == ["00", "0", "[0, 0, 0]", "0"]


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        (
            'modbus_add_rw_signal("0.0.0.0", 255, 5, 0, 15, 1, "x")',
            "read_register_count must be an int of 1 to 123",
        ),
        (
            'modbus_add_rw_signal("0.0.0.0", 255, 5, 1, 15, 124, "x")',
            "write_register_count must be an int of 1 to",
        ),
        ('modbus_add_rw_signal("", 255, 5, 1, 15, 1, "x")', "IP must be a text that is not empty"),
        ('modbus_add_rw_signal("0.0.0.0", 255, 5, 1, 15, 1)', "missing argument signal_name"),
        ('modbus_set_output_register("rw", [1, 2, 3])', "(or a list of 1 to 2)"),
        ('modbus_set_signal_watchdog("rw", 301)', "new_timeout_in_sec must be 0 to 300, not 301"),
        ('modbus_set_signal_watchdog("rw", "5")', "new_timeout_in_sec must be a number"),
        ('modbus_get_error("rw", 3)', "error_source must be one of 0, 1, 2, not 3"),
        ('modbus_get_error("nope")', "no Modbus signal 'nope'"),
        ('modbus_get_time_since_signal_invalid("nope")', "no Modbus signal 'nope'"),
    ],
)
def test_a_modbus_call_the_manual_rules_out_is_a_runtime_exception_at_its_line(
    line: str, problem: str
) -> None:
    _, events = run(f'def prog():\n  modbus_add_rw_signal("0.0.0.0", 255, 0, 4, 8, 2, "rw")\n  {line}\nend\n')
    ((text, at, _),) = faults(events)
    assert problem in text and at == 3, text
