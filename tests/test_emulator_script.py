"""URScript I/O calls sent to the emulator's primary/secondary ports show up on RTDE, as on a controller."""

from __future__ import annotations

import time

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, PrimaryClient, RtdeClient
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.ports.script import run_script


def test_io_calls_set_the_outputs_a_controller_shows() -> None:
    model = ControllerModel("5.15.0")
    program = """def prog():
      set_standard_digital_out(3, True)
      set_configurable_digital_out(1, True)
      set_tool_digital_out(0, True)
      set_standard_analog_out(1, 0.25)
      textmsg("not an I/O call")
      movej([0, 0, 0, 0, 0, 0])
    end"""
    applied = run_script(model, program)
    assert applied == [
        "set_standard_digital_out(3, True)",
        "set_configurable_digital_out(1, True)",
        "set_tool_digital_out(0, True)",
        "set_standard_analog_out(1, 0.25)",
    ]
    bits = model.values["actual_digital_output_bits"]
    assert bits == (1 << 3) | (1 << (8 + 1)) | (1 << 16)
    assert model.values["standard_analog_output1"] == 0.25
    run_script(model, "set_standard_digital_out(3, False)\nset_standard_digital_out(0, true)")
    assert model.values["actual_digital_output_bits"] == 1 | (1 << 9) | (1 << 16)


@pytest.mark.parametrize(
    "line",
    [
        "set_standard_digital_out(8, True)",  # no pin 8
        "set_tool_digital_out(2, True)",  # the tool has two
        "set_standard_digital_out(1, 0.5)",  # not a bool
        "set_standard_analog_out(2, 0.5)",  # two analog outputs
        "set_standard_digital_out(x, True)",  # not a literal
        "garbage((((",
    ],
)
def test_calls_a_controller_would_refuse_change_nothing(line: str) -> None:
    model = ControllerModel("5.15.0")
    before = dict(model.values)
    assert run_script(model, line) == [] and model.values == before


def test_a_script_on_the_primary_port_shows_on_rtde_and_not_from_a_read_only_port() -> None:
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=0,
        secondary_port=0,
        secondary_read_only_port=0,
        realtime_port=None,
        dashboard_port=None,
    )
    emu = EmulatorThread(config).start()
    try:
        with PrimaryClient("127.0.0.1", emu.ports["secondary_read_only"]) as quiet:
            quiet._sock.sendall(b"set_standard_digital_out(5, True)\n")  # type: ignore[union-attr]
        with PrimaryClient("127.0.0.1", emu.ports["primary"]) as client:
            client.send_script("set_standard_digital_out(2, True)\nset_standard_analog_out(0, 0.5)")
            time.sleep(0.3)
        with RtdeClient("127.0.0.1", emu.ports["rtde"]) as robot:
            robot.setup_outputs(["actual_digital_output_bits", "standard_analog_output0"], 125)
            robot.start()
            record = robot.receive()
        assert record.actual_digital_output_bits == 1 << 2  # not bit 5: read-only ports ignore scripts
        assert record.standard_analog_output0 == 0.5
        with PrimaryClient("127.0.0.1", emu.ports["secondary"], timeout=2) as client:
            state = next(m for m in client if m.NAME == "robot_state")
        board = state["masterboard_data"]
        assert board.digital_output_bits == 1 << 2 and board.analog_output0 == 0.5 and board.safety_mode == 1
    finally:
        emu.stop()


def test_serve_log_says_why_a_program_was_refused_and_when_a_long_one_is_read_later(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """ur_rtde's ScriptClient.sendScript() with no argument sends its 1,175-line control script
    with its placeholders unfilled: the log said "(0 I/O calls run)" and nothing else, as a long
    program is read off the control loop and its syntax error went only to primary clients (none
    were listening)."""
    config = EmulatorConfig(
        rtde_port=None, primary_port=0, secondary_port=0, secondary_read_only_port=None, realtime_port=None,
        dashboard_port=None,
    )  # fmt: skip
    body = "".join(f"  x{i} = {i}\n" for i in range(2500))  # over 16 kB
    program = f"def rtde_control():\n  global reg_offset_float = # a placeholder left\n{body}end\n"
    emu = EmulatorThread(config).start()
    try:
        with caplog.at_level("INFO", logger="rtde_spec.emulator"):
            with PrimaryClient("127.0.0.1", emu.ports["secondary"]) as client:
                client.send_script(program)
                deadline = time.monotonic() + 10
                while "program refused at line" not in caplog.text and time.monotonic() < deadline:
                    time.sleep(0.05)
    finally:
        emu.stop()
    assert "characters, read off the control loop" in caplog.text
    assert "I/O calls run" not in caplog.text
    assert "program refused at line 3:" in caplog.text and "syntax_error_on_line:3" in caplog.text


def test_a_refused_programs_log_line_holds_no_control_characters_or_lone_surrogates(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A program's text is the client's: undecodable bytes (kept as lone surrogates) and escape
    sequences. In the log line of its runtime exception they broke pytest-xdist's report of a passing
    fuzz test (no UTF-8 encoding of a lone surrogate) and could drive a terminal."""
    model = ControllerModel("5.15.0")
    with caplog.at_level("WARNING", logger="rtde_spec.emulator"):
        assert run_script(model, 'def p():\n  x = "\udcff\x1b[2J" +\nend\n') == []
    (line,) = [r.getMessage() for r in caplog.records if "refused" in r.getMessage()]
    line.encode("utf-8")  # no lone surrogate left
    assert "\\udcff" in line and "\\x1b[2J" in line and "\x1b" not in line


def test_a_long_program_sent_again_starts_without_being_parsed_again() -> None:
    """URCL sends its 49 kB program again for each test, then waits 100 ms for it to connect back;
    parsing it took most of the ~60-200 ms the emulator needed. The second program runs the tree the
    first one's parse made, with tables of its own (interpreter mode adds functions to them)."""
    config = EmulatorConfig(
        rtde_port=None, primary_port=0, secondary_port=None, realtime_port=None, dashboard_port=None
    )
    body = "".join(f"  x{i} = {i}\n" for i in range(2500))  # over 16 kB: read off the control loop
    program = f"def driver():\n  def helper():\n    return 1\n  end\n{body}  sleep(30)\nend\n"
    emu = EmulatorThread(config).start()
    try:
        model = emu.emulator.model
        started = []
        with PrimaryClient("127.0.0.1", emu.ports["primary"]) as client:
            for _ in range(2):
                client.send_script(program)
                deadline = time.monotonic() + 10
                while model.program in (None, *started) and time.monotonic() < deadline:
                    time.sleep(0.01)
                assert model.program is not None and model.program not in started
                started.append(model.program)
        first, second = (p.script for p in started)
        assert second.functions["helper"] is first.functions["helper"]  # the same tree: parsed once
        assert second.functions is not first.functions and second.main is not first.main
        assert model.program is started[1] and model.program.fault is None
    finally:
        emu.stop()
