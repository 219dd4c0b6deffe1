"""Programs as PolyScope generates them run on the emulator, and what their preamble sets shows where
clients look.

Every program PolyScope saves or plays is a `def <name>():` whose preamble the installation writes:
I/O domains, the tool connector's modes and serial interface, how outputs follow the program,
Modbus signals, gravity, TCP and payload, a step counter thread, then `$ N "label"` markers before
each program node and the URCaps' own preambles (Robotiq's grippers talk to their driver with
socket_set_var / socket_get_var / socket_read_byte_list, force/torque and other daemons through
rpc_factory handles). The preambles here are written for these tests in the shapes of real saved
programs (not copied from them): UniversalRobots/URScript_Examples execution-time/timing_debug.script
(PolyScope 5.22), UniversalRobots/Universal_Robots_ROS2_Driver's URSim urcap_ros_control.script,
o2ac/o2ac-ur's urscripts (UR5e with Robotiq_Grippers 1.8, rs485 and External Control URCaps),
Automation-Research-Team/aist_robotiq's o2as_skills scripts (CB3 with Robotiq's force/torque sensor
and 2F gripper URCaps), glinvad/UR_Scripting's UR_Code programs, and UR's client library's PolyScope X
test programs (`$` markers with no def).
"""

from __future__ import annotations

import itertools
import socket
import threading
import time
import xmlrpc.server
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, PrimaryClient, RtdeClient
from rtde_spec._generated.enums import ProgramState
from rtde_spec.emulator.controller.model import BACKGROUND_PARSE, ControllerModel
from rtde_spec.emulator.urscript import ScriptFault, parse

# A 5.x preamble in the order PolyScope writes it (tool I/O first, then domains and the step counter)
E_SERIES_PREAMBLE = """def unnamed():
  global _hidden_verificationVariable=0
  modbus_add_signal("0.0.0.0", 255, 0, 0, "MODBUS_1", False)
  modbus_set_signal_update_frequency("MODBUS_1", 10)
  set_tool_communication(True, 115200, 0, 1, 1.5, 3.5)
  set_tool_output_mode(0)
  set_tool_digital_output_mode(0, 1)
  set_tool_digital_output_mode(1, 2)
  set_tool_voltage(24)
  set_safety_mode_transition_hardness(1)
  set_standard_analog_input_domain(0, 1)
  set_standard_analog_input_domain(1, 0)
  set_tool_analog_input_domain(0, 0)
  set_tool_analog_input_domain(1, 1)
  set_analog_outputdomain(0, 0)
  set_analog_outputdomain(1, 1)
  set_input_actions_to_default()
  set_runstate_standard_digital_outputs([2])
  set_runstate_standard_digital_output_to_value(2, 3)
  step_count_1a2b = 0.0
  thread Step_Counter_Thread_3c4d():
    while (True):
      step_count_1a2b = step_count_1a2b + 1.0
      sync()
    end
  end
  run Step_Counter_Thread_3c4d()
  set_target_payload(1.200000, [0.001000, -0.018000, 0.049000], [0.002, 0.002, 0.002, 0.0, 0.0, 0.0])
  set_tcp(p[0.0,0.0,0.165,0.0,0.0,0.0])
  set_gravity([0.0, 0.0, 9.82])
  # begin: URCap Installation Node
  #   Source: Some Gripper, 1.0.0, Some Vendor
  #   Type: Gripper
  global gripper_rpc=rpc_factory("xmlrpc", "http://127.0.0.1:1/RPC2")
  # end: URCap Installation Node
  global Waypoint_1_p=p[-.120000000000, -.430000000000, .140000000000, .000000000000, 3.11, .04]
  $ 2 "BeforeStart"
  $ 3 "var_1≔3"
  global var_1=3
  while (True):
    $ 4 "Robot Program"
    $ 5 "Wait: 0.1"
    sleep(0.1)
    $ 6 "Waypoint_1" "breakAfter"
    textmsg("at waypoint")
  end
end
"""
# a CB3 3.x preamble: set_payload, no tool modes or serial interface, no transition hardness
CB3_PREAMBLE = """def myProg():
  set_standard_analog_input_domain(0, 1)
  set_standard_analog_input_domain(1, 1)
  set_tool_analog_input_domain(0, 1)
  set_tool_analog_input_domain(1, 1)
  set_analog_outputdomain(0, 0)
  set_analog_outputdomain(1, 0)
  set_tool_voltage(0)
  set_input_actions_to_default()
  set_tcp(p[0.0,0.0,0.0,0.0,0.0,0.0])
  set_payload(0.5)
  set_gravity([0.0, 0.0, 9.82])
  $ 1 "Robot Program"
  textmsg("ran")
end
"""


def start(script: str, version: str = "5.15.0") -> tuple[ControllerModel, list[Any]]:
    """`script` started on a fresh model (up to its first wait); the events so far."""
    model = ControllerModel(version)
    model.run_script(script)
    return model, model.drain_events()


def steps(
    model: ControllerModel, count: int, until: Callable[[], bool] = lambda: False, pace: float = 0.0
) -> list[Any]:
    """`count` control steps (or until `until()`), the events they gave; `pace` s of real time a step
    (a remote procedure call is answered in real time, as the server's control loop steps in it)."""
    events: list[Any] = []
    for _ in range(count):
        model.tick(model.step + 1)
        events += model.drain_events()
        if until():
            break
        if pace:
            time.sleep(pace)
    return events


def faults(events: list[Any]) -> list[tuple[str, int]]:
    return [(e.text, e.line) for e in events if e.kind == "runtime_exception"]


def texts(events: list[Any]) -> list[str]:
    return [e.text for e in events if e.kind == "text"]


# --- the preamble runs and sets what clients see -------------------------------------------------------


def test_an_e_series_preamble_runs_and_sets_the_tool_io_and_domains_it_names() -> None:
    model, events = start(E_SERIES_PREAMBLE)
    events += steps(model, 500)
    assert faults(events) == [] and model.program is not None
    values = model.values
    assert values["analog_io_types"] == 0b1001  # input 0 and output 1 in volts
    assert values["tool_analog_input_types"] == 0b10
    modes = ("tool_output_mode", "tool_digital_output0_mode", "tool_digital_output1_mode")
    assert [values[name] for name in modes] == [0, 1, 2]
    assert values["tool_output_voltage"] == 24
    assert values["payload"] == 1.2 and values["payload_cog"] == (0.001, -0.018, 0.049)
    assert model.tool_communication == {
        "tool_communication_is_enabled": True, "baud_rate": 115200, "parity": 0, "stop_bits": 1,
        "rx_idle_chars": 1.5, "tx_idle_chars": 3.5,
    }  # fmt: skip
    assert values["actual_digital_output_bits"] & 0b100  # runstate 3: high while the program runs
    assert model.program.globals["step_count_1a2b"] >= 499  # the counter thread's sync() loop
    assert texts(events).count("at waypoint") >= 9
    assert model.program.settings["modbus_signals"]["MODBUS_1"]["update_frequency"] == 10  # type: ignore[attr-defined]
    model.stop_program()
    assert not model.values["actual_digital_output_bits"] & 0b100  # and low once it stopped


def test_a_cb3_preamble_runs_on_a_cb3_controller() -> None:
    model, events = start(CB3_PREAMBLE, "3.15.8")
    events += steps(model, 10)
    assert faults(events) == [] and texts(events) == ["ran"]
    assert model.values["analog_io_types"] == 0b0011 and model.values["tool_analog_input_types"] == 0b11


def test_tool_modes_and_the_serial_interface_are_e_series_only() -> None:
    _, events = start("def p():\n  set_tool_output_mode(0)\nend\n", "3.15.8")
    assert faults(events) == [("compile_error_name_not_found:set_tool_output_mode:", 2)]


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ("set_standard_analog_input_domain(2, 1)", "port must be one of 0, 1"),
        ("set_tool_analog_input_domain(0, 2)", "domain must be one of 0, 1"),
        ("set_tool_digital_output_mode(0, 0)", "mode must be one of 1, 2, 3"),
        ("set_tool_communication(True, 115201, 0, 1, 1.5, 3.5)", "baud_rate must be one of"),
        ("set_tool_communication(True, 115200, 0, 1, 0.5, 3.5)", "rx_idle_chars must be 1 to 40"),
        ("set_runstate_tool_digital_output_to_value(1, 6)", "state must be one of 0, 1, 2, 3, 4, 5"),
        ('modbus_set_signal_update_frequency("nope", 10)', "no Modbus signal 'nope'"),
        ('modbus_add_signal("1.2.3.4", 255, 0, 0, "a_name_of_21_chars___")', "1 to 20 characters"),
    ],
)
def test_a_setting_outside_the_manuals_values_is_a_runtime_exception(line: str, problem: str) -> None:
    _, events = start(f"def p():\n  {line}\nend\n")
    ((text, at),) = faults(events)
    assert problem in text and at == 2


def test_modbus_signals_a_program_sets_read_back_and_inputs_read_nothing() -> None:
    """PolyScope's Set, Wait and If nodes on Modbus signals call these (UR's URScript_Examples
    modbus/ programs too); no device answers, so an input reads False or 0."""
    model, events = start(
        "def p():\n"
        '  modbus_add_signal("0.0.0.0", 255, 0, 0, "din", False)\n'
        '  modbus_add_signal("0.0.0.0", 255, 1, 1, "dout", False)\n'
        '  modbus_add_signal("0.0.0.0", 255, 2, 3, "reg", False)\n'
        '  modbus_add_signal("0.0.0.0", 255, 9, 16, "regs", False, 3)\n'
        '  modbus_add_signal("0.0.0.0", 255, 0, 0, "dins", True, 4)\n'
        '  modbus_set_output_signal("dout", True, False)\n'
        '  modbus_set_output_register("reg", 65535)\n'
        '  modbus_set_output_register("regs", [7, 8])\n'
        '  textmsg(modbus_get_signal_status("din", False), modbus_get_signal_status("dout"))\n'
        '  textmsg(modbus_get_signal_status("reg", False), modbus_get_signal_status("regs"))\n'
        '  textmsg(modbus_get_signal_status("dins")[3])\n'
        '  modbus_send_custom_command("0.0.0.0", 255, 6, [17, 32, 2, 88])\n'
        '  modbus_delete_signal("din")\n'
        '  modbus_get_signal_status("din", False)\n'
        "end\n"
    )
    events += steps(model, 3)
    assert texts(events) == ["FalseTrue", "65535[7, 8, 0]", "False"]  # 4 inputs: a list
    assert faults(events) == [
        ("modbus_get_signal_status: no Modbus signal 'din' (modbus_add_signal adds it)", 15)
    ]


@pytest.mark.parametrize(
    ("line", "problem"),
    [
        ('modbus_set_output_signal("din", True, False)', "'din' is no digital output"),
        ('modbus_set_output_register("dout", 1, False)', "'dout' is no register output"),
        ('modbus_set_output_signal("dout", 1, False)', "the value must be a bool, not 1"),
        ('modbus_set_output_register("reg", 65536)', "the value must be an int of 0 to 65535, not 65536"),
        ('modbus_set_output_register("regs", [1, 2, 3, 4])', "an int of 0 to 65535 (or a list of 1 to 3)"),
        ('modbus_send_custom_command("0.0.0.0", 255, 6, [256])', "data a list of bytes"),
    ],
)
def test_a_modbus_write_the_signal_cannot_take_is_a_runtime_exception(line: str, problem: str) -> None:
    signals = (
        '  modbus_add_signal("0.0.0.0", 255, 0, 0, "din", False)\n'
        '  modbus_add_signal("0.0.0.0", 255, 1, 1, "dout", False)\n'
        '  modbus_add_signal("0.0.0.0", 255, 2, 3, "reg", False)\n'
        '  modbus_add_signal("0.0.0.0", 255, 9, 16, "regs", False, 3)\n'
    )
    _, events = start(f"def p():\n{signals}  {line}\nend\n")
    ((text, at),) = faults(events)
    assert problem in text and at == 6


# --- program labels ------------------------------------------------------------------------------------


def test_labels_run_and_say_where_each_thread_is() -> None:
    model, events = start(
        'def prog():\n  $ 1 "BeforeStart"\n  thread t():\n    $ 7 "Thread_1"\n    while True:\n'
        '      $ 8 "sync()"\n      sync()\n    end\n  end\n  run t()\n  $ 2 "Robot Program"\n'
        '  $ 3 "Waypoint_1" "breakAfter"\n  sleep(1)\nend\n'
    )
    events += steps(model, 5)
    assert faults(events) == [] and model.program is not None
    assert sorted(model.program.thread_labels()) == [("prog", 3, "Waypoint_1"), ("t", 8, "sync()")]


def test_polyscope_x_labels_stand_before_a_program_with_no_def() -> None:
    model, events = start('$ 1 "ur-program"\n$ 2 "ur-modules"\n$ 6 "ur-wait"\nsleep(0.01)')
    events += steps(model, 10, lambda: model.program is None)
    assert faults(events) == [] and model.program is None
    assert [e.kind for e in events] == ["program_started", "program_stopped"]


@pytest.mark.parametrize("label", ['$ "x"', "$ 1", '$ 1.5 "x"', '$\n1 "x"'])
def test_a_label_without_its_number_and_text_is_a_syntax_error(label: str) -> None:
    with pytest.raises(ScriptFault, match="syntax_error_on_line:2"):
        parse(f"def p():\n  {label}\nend\n")


# --- arguments by name, as URCap preambles call their functions -------------------------------------


@pytest.mark.parametrize("version", ["3.15.8", "5.15.0"])
def test_a_force_node_s_tool_feature_gives_force_mode_the_tool_s_pose(version: str) -> None:
    """PolyScope writes `force_mode(tool_pose(), ...)` for a Force node on its Tool feature."""
    model, events = start(
        "def p():\n  set_tcp(p[0, 0, 0.1, 0, 0, 0])\n"
        "  force_mode(tool_pose(), [0, 0, 1, 0, 0, 0], [0, 0, 5, 0, 0, 0], 2, [0.1, 0.1, 0.1, 0.3, 0.3, 0.3])"
        "\n"
        "  textmsg(pose_dist(tool_pose(), get_actual_tcp_pose()))\n"
        "  textmsg(pose_dist(tool_pose(), get_actual_tool_flange_pose()))\n  end_force_mode()\nend\n",
        version,
    )
    events += steps(model, 5)
    assert not faults(events)
    assert texts(events) == ["0", "0.1"]


def test_user_functions_take_their_parameters_by_name() -> None:
    _, events = start(
        "def p():\n"
        '  def rq_is_object_detected(gripper_socket="1", timeout=2):\n'
        "    return str_cat(gripper_socket, timeout)\n  end\n"
        '  textmsg(rq_is_object_detected(gripper_socket="2"))\n'
        '  textmsg(rq_is_object_detected("3", timeout=5))\n'
        "  textmsg(rq_is_object_detected(timeout=7))\nend\n"
    )
    assert faults(events) == [] and texts(events) == ["22", "35", "17"]


@pytest.mark.parametrize(
    ("call", "problem"),
    [
        ("f(b=1)", "no parameter b"),
        ("f(1, a=2)", "a given twice"),
        ("f(a=1, a=2)", "a given twice"),
        ("f()", "takes 1 arguments, got 0"),
        ("f(1, 2)", "takes 1 arguments, got 2"),
    ],
)
def test_a_name_the_function_does_not_take_is_a_compile_error(call: str, problem: str) -> None:
    _, events = start(f"def p():\n  def f(a):\n    return a\n  end\n  {call}\nend\n")
    assert faults(events) == [(f"compile_error: f {problem}", 5)]


# --- how outputs follow the program (runstate) ------------------------------------------------------


def test_runstate_choices_set_the_outputs_when_programs_start_and_end() -> None:
    model, _ = start(
        "def p():\n"
        "  set_runstate_standard_digital_output_to_value(0, 2)\n"  # high when not running
        "  set_runstate_configurable_digital_output_to_value(1, 3)\n"  # high while running
        "  set_runstate_tool_digital_output_to_value(0, 4)\n"  # low on an unscheduled end
        "  set_tool_digital_out(0, True)\n  sleep(0.1)\nend\n"
    )
    bits = model.values["actual_digital_output_bits"]
    assert (bits & 1, bits >> 9 & 1, bits >> 16 & 1) == (0, 1, 1)
    steps(model, 100, lambda: model.program is None)
    bits = model.values["actual_digital_output_bits"]
    assert (bits & 1, bits >> 9 & 1, bits >> 16 & 1) == (1, 0, 1)  # a scheduled end: tool output kept
    model.run_script("def q():\n  set_tool_digital_out(0, True)\n  x = 1 / 0\nend\n")
    steps(model, 5, lambda: model.program is None)
    bits = model.values["actual_digital_output_bits"]
    assert (bits & 1, bits >> 9 & 1, bits >> 16 & 1) == (1, 0, 0)  # the runtime exception: low


# --- a blocking popup suspends the program ---------------------------------------------------------


def test_a_blocking_popup_pauses_the_program_until_it_is_played_again() -> None:
    model, events = start(
        'def p():\n  popup("press play", "Robotiq Grippers", False, True, blocking=True)\n'
        '  textmsg("went on")\nend\n'
    )
    events += steps(model, 50)
    assert [e.text for e in events if e.kind == "popup"] == ["press play"]
    assert model.program is not None and model.program_state == ProgramState.PAUSED
    assert texts(events) == []
    assert model.play()
    events = steps(model, 10, lambda: model.program is None)
    assert texts(events) == ["went on"] and model.program is None


# --- reading the I/O and the registers ------------------------------------------------------------------


def test_the_io_reads_give_what_the_outputs_and_inputs_show() -> None:
    model = ControllerModel("5.22.0")
    model.values["actual_digital_input_bits"] = (1 << 3) | (1 << 16)  # standard input 3, tool input 0
    model.values["tool_analog_input1"] = 0.7
    model.run_script(
        "def p():\n  set_standard_digital_out(5, True)\n  set_standard_analog_out(1, 0.25)\n"
        "  write_output_integer_register(24, 41)\n"
        "  write_output_integer_register(24, read_output_integer_register(24) + 1)\n"
        "  write_output_float_register(25, 2.5)\n  write_output_boolean_register(10, True)\n"
        "  textmsg(str_cat(get_standard_digital_in(3), get_standard_digital_out(5)))\n"
        "  textmsg(str_cat(get_digital_in(8), get_tool_digital_in(1)))\n"
        "  textmsg(str_cat(get_analog_in(3), get_standard_analog_out(1)))\n"
        "  textmsg(str_cat(read_output_integer_register(24), read_output_float_register(25)))\n"
        "  textmsg(read_output_boolean_register(10))\n"
        '  textmsg(str_cat(length([1, 2, 3]), length("abcd")))\n'
        "  t = time(2)\n  textmsg(t.sec >= 0 and t.nanosec < 1000000000)\nend\n"
    )
    # on a loaded machine the step's time slice may end before the script does: it goes on in the
    # next steps (once failed in a README run beside another suite, the last textmsg missing)
    events = model.drain_events() + steps(model, 50, lambda: model.program is None)
    assert model.program is None
    assert faults(events) == []
    assert texts(events) == ["TrueTrue", "TrueFalse", "0.70.25", "422.5", "True", "34", "True"]
    assert model.values["output_int_register_24"] == 42


def test_set_pos_places_the_simulated_arm_at_once() -> None:
    q = [0.5, -1.2, 1.0, -1.3, -1.57, 0.2]
    model, events = start(f"def p():\n  set_pos({q})\n  textmsg(get_actual_joint_positions())\nend\n")
    steps(model, 2)
    assert faults(events) == [] and list(model.values["actual_q"]) == pytest.approx(q)


# --- Robotiq's socket requests ---------------------------------------------------------------------


class GripperDriver:
    """A stand-in for Robotiq's driver on its socket: SET answers "ack", GET "<name> <value>"."""

    def __init__(self, answer: bool = True) -> None:
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.received: list[bytes] = []
        self.answer = answer
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.server.accept()
        with conn:
            pending = b""
            while data := conn.recv(4096):
                pending += data
                while b"\n" in pending:
                    line, _, pending = pending.partition(b"\n")
                    self.received.append(line)
                    if not self.answer:
                        continue
                    words = line.split()
                    if words[0] == b"SET":
                        conn.sendall(b"ack")
                    elif words[0] == b"GET":
                        conn.sendall(words[1] + b" 3\n" if words[1] != b"FWV" else b">GRP-1.2<\nrest")

    def close(self) -> None:
        self.server.close()


@pytest.fixture
def driver() -> Iterator[GripperDriver]:
    server = GripperDriver()
    yield server
    server.close()


def test_robotiq_style_requests_go_out_and_their_answers_come_back(driver: GripperDriver) -> None:
    model, events = start(
        "def p():\n"
        f'  socket_open("127.0.0.1", {driver.port}, "1")\n'
        '  socket_set_var("SID", 9, "1")\n'
        '  ack = socket_read_byte_list(3, "1")\n'
        "  textmsg(ack)\n"
        '  textmsg(socket_get_var("STA", "1"))\n'
        '  socket_send_line("GET FWV", "1")\n'
        '  textmsg(socket_read_string("1", prefix=">", suffix="<"))\n'
        '  textmsg(socket_read_string("1"))\nend\n'
    )
    # steps paced in real time, as the server's control loop runs them: the driver's thread answers
    # in real time, and 1,000 unpaced steps (its 2 s time-out in controller time) once passed
    # before it had (a CI-like run beside a CPU hog)
    events += steps(model, 1000, lambda: model.program is None, pace=0.002)
    assert faults(events) == []
    assert texts(events) == ["[3, 97, 99, 107]", "3", "GRP-1.2", "\nrest"]
    assert driver.received == [b"SET SID 9", b"GET STA", b"GET FWV"]


def test_requests_no_one_answers_time_out_as_the_manual_says() -> None:
    silent = GripperDriver(answer=False)
    try:
        model, events = start(
            f'def p():\n  socket_open("127.0.0.1", {silent.port}, "1")\n'
            '  textmsg(socket_get_var("STA", "1"))\n  textmsg(socket_read_byte_list(3, "1", 0.5))\n'
            '  textmsg(socket_read_string("1", timeout=0.1))\n  textmsg(socket_get_var("STA", "none"))\nend\n'
        )
        events += steps(model, 2000, lambda: model.program is None)
    finally:
        silent.close()
    assert faults(events) == [] and texts(events) == ["0", "[0, -1, -1, -1]", "", "0"]
    assert 2.5 < model.time < 3.0  # 2 s for the GET, 0.5 s for the bytes, 0.1 s for the string


# --- remote procedure calls (rpc_factory) ----------------------------------------------------------


@pytest.fixture
def xmlrpc_server() -> Iterator[int]:
    server = xmlrpc.server.SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
    server.register_function(lambda a, b: a + b, "add")
    target = {"x": -0.45, "y": -0.13, "z": 0.4, "rx": 0.0, "ry": 3.14, "rz": 0.0}
    server.register_function(lambda: target, "getTarget")
    server.register_function(lambda pose: sorted(pose), "keys")
    server.register_function(lambda: {"width": 50, "busy": False}, "status")
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield server.server_address[1]
    server.shutdown()
    server.server_close()


def test_rpc_calls_reach_the_server_and_bring_its_answer_back(xmlrpc_server: int) -> None:
    model, events = start(
        f'def p():\n  camera = rpc_factory("xmlrpc", "http://127.0.0.1:{xmlrpc_server}/RPC2")\n'
        "  textmsg(camera.add(1, 2))\n"
        "  target = camera.getTarget()\n  textmsg(target)\n"
        "  textmsg(camera.keys(p[1, 2, 3, 0, 0, 0]))\n"
        "  textmsg(camera.status().width)\n"
        "  camera.closeXMLRPCClientConnection()\n  movel(target, a=1.2, v=0.25)\nend\n"
    )
    events += steps(model, 5000, lambda: model.program is None, pace=0.002)
    assert faults(events) == [] and model.program is None
    assert texts(events) == ["3", "p[-0.45, -0.13, 0.4, 0, 3.14, 0]", "[rx, ry, rz, x, y, z]", "50"]
    assert list(model.values["actual_TCP_pose"])[:3] == pytest.approx([-0.45, -0.13, 0.4], abs=1e-6)


def test_a_handle_no_one_calls_costs_nothing() -> None:
    _, events = start(
        'def p():\n  idle = rpc_factory("xmlrpc", "http://127.0.0.1:1/RPC2")\n  textmsg("fine")\nend\n'
    )
    assert faults(events) == [] and texts(events) == ["fine"]


@pytest.mark.parametrize(("call", "problem"), [("nope()", "nope"), ("add(1)", "add")])
def test_a_failed_call_stops_the_program_at_its_line(xmlrpc_server: int, call: str, problem: str) -> None:
    model, events = start(
        f'def p():\n  s = rpc_factory("xmlrpc", "http://127.0.0.1:{xmlrpc_server}/RPC2")\n'
        f"  x = s.{call}\nend\n"
    )
    events += steps(model, 5000, lambda: model.program is None, pace=0.002)
    ((text, line),) = faults(events)
    assert text.startswith(f"XML-RPC {problem}") and line == 3


def test_a_call_to_a_handle_of_a_pstream_url_is_refused_naming_it() -> None:
    _, events = start('def p():\n  s = rpc_factory("xmlrpc", "127.0.0.1:8080")\n  s.go()\nend\n')
    ((text, line),) = faults(events)
    assert "pstream is not modelled" in text and line == 3


# --- on the ports, as a client sees the program -----------------------------------------------------


@pytest.fixture
def emulator() -> Iterator[EmulatorThread]:
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=None, realtime_port=None, dashboard_port=None
    )
    emu = EmulatorThread(config).start()
    try:
        yield emu
    finally:
        emu.stop()


def _robot_state(port: int, done: Callable[[Any], bool]) -> Any:
    deadline = time.monotonic() + 10
    with PrimaryClient("127.0.0.1", port, timeout=5) as client:
        for message in client:
            if message.NAME == "robot_state" and done(message):
                return message
            assert time.monotonic() < deadline, "the Robot State never showed it"
    raise AssertionError("the primary port closed")


def test_rtde_and_the_robot_state_show_what_the_preamble_set(emulator: EmulatorThread) -> None:
    ports = emulator.ports
    fields = ["analog_io_types", "tool_analog_input_types", "tool_output_mode", "tool_digital_output1_mode"]
    with RtdeClient("127.0.0.1", ports["rtde"]) as rtde:
        rtde.setup_outputs(fields, 10)
        rtde.start()
        with PrimaryClient("127.0.0.1", ports["primary"]) as client:
            client.send_script(E_SERIES_PREAMBLE)
        deadline = time.monotonic() + 10
        while (record := rtde.receive(2)).tool_digital_output1_mode != 2:
            assert time.monotonic() < deadline, "RTDE never showed the preamble"
        shown = (record.analog_io_types, record.tool_analog_input_types, record.tool_output_mode)
        assert shown == (0b1001, 0b10, 0)

    def enabled(message: Any) -> bool:
        return bool(message["tool_comm_info"].tool_communication_is_enabled)

    state = _robot_state(ports["primary"], enabled)
    comm, modes, tool = state["tool_comm_info"], state["tool_mode_info"], state["tool_data"]
    assert (comm.baud_rate, comm.parity, comm.stop_bits, comm.rx_idle_chars, comm.tx_idle_chars) == (
        115200, 0, 1, 1.5, 3.5,
    )  # fmt: skip
    assert (modes.digital_output_mode_pin0, modes.digital_output_mode_pin1) == (1, 2)
    assert (tool.analog_input_range0, tool.analog_input_range1, tool.tool_output_voltage) == (0, 1, 24)
    board = state["masterboard_data"]
    assert (board.analog_input_range0, board.analog_input_range1) == (1, 0)


def test_play_of_a_long_program_is_accepted_while_it_is_read() -> None:
    model = ControllerModel("5.15.0")
    lines = "".join(f"  x_{i} = {i}\n" for i in range(2000))
    model.load_program(f'def long_one():\n{lines}  textmsg("read and ran")\nend\n')
    assert model.play()  # the program is read off the control loop: play is accepted meanwhile
    deadline = time.monotonic() + 10
    events: list[Any] = []
    while "read and ran" not in texts(events):
        assert time.monotonic() < deadline, "the long program never ran"
        time.sleep(0.01)
        events += steps(model, 1)


def test_a_long_generated_program_plays_from_the_dashboard_as_a_user_plays_it(tmp_path: Path) -> None:
    """o2ac's programs are 75-100 kB with Robotiq's preamble: read off the control loop, and `play`
    answers "Starting program" (it answered "Failed to execute: play" for a program that then ran)."""
    programs = tmp_path / "programs"
    programs.mkdir()
    helper = '  def urcap_helper_{}(gripper_socket="1"):\n    return 0\n  end\n'
    helpers = "".join(helper.format(i) for i in range(700))
    text = E_SERIES_PREAMBLE.replace("  # end: URCap Installation Node\n", helpers + "  # end: URCap", 1)
    assert len(text) > BACKGROUND_PARSE
    (programs / "unnamed.script").write_text(text, encoding="utf-8")
    config = EmulatorConfig(
        rtde_port=0, primary_port=None, secondary_port=None, realtime_port=None, dashboard_port=0,
        programs=programs,
    )  # fmt: skip
    emu = EmulatorThread(config).start()
    try:
        with socket.create_connection(("127.0.0.1", emu.ports["dashboard"]), timeout=5) as dashboard:
            replies = dashboard.makefile("rb")
            replies.readline()

            def ask(command: str) -> str:
                dashboard.sendall(command.encode() + b"\n")
                return replies.readline().decode().strip()

            assert ask("load unnamed.urp") == "Loading program: unnamed.urp"  # the .script beside it
            with RtdeClient("127.0.0.1", emu.ports["rtde"]) as rtde:
                rtde.setup_outputs(["runtime_state", "tool_digital_output1_mode"], 10)
                rtde.start()
                assert ask("play") == "Starting program"
                deadline = time.monotonic() + 10
                while (record := rtde.receive(2)).tool_digital_output1_mode != 2:
                    assert time.monotonic() < deadline, "the program never ran its preamble"
                assert record.runtime_state == ProgramState.RUNNING
            assert ask("programState") == "PLAYING unnamed.urp"
    finally:
        emu.stop()


LABELLED = """def prog():
  $ 1 "BeforeStart"
  thread Thread_1():
    while True:
      $ 7 "Thread_1"
      sleep(0.3)
      $ 8 "Wait: 0.3"
      sleep(0.3)
    end
  end
  threadId_Thread_1 = run Thread_1()
  while True:
    $ 2 "Robot Program"
    $ 3 "MoveJ"
    sleep(0.25)
    $ 4 "Waypoint_1" "breakAfter"
    sleep(0.25)
  end
end
"""


def test_the_primary_port_sends_program_threads_with_each_threads_last_label() -> None:
    """The Program Threads message (robot message 14): each running thread's last `$` label, as
    PolyScope shows where a program is. Before, the labels were kept and never sent."""
    config = EmulatorConfig(
        rtde_port=None, primary_port=0, secondary_port=None, secondary_read_only_port=None,
        realtime_port=None, dashboard_port=None,
    )  # fmt: skip
    seen: list[list[tuple[str, int, str]]] = []
    with EmulatorThread(config) as emu, PrimaryClient("127.0.0.1", emu.ports["primary"]) as client:
        client.send_script(LABELLED)
        end = time.monotonic() + 1.5
        for message in client:
            if message.NAME == "program_threads_message":
                seen.append([(t.thread_name, t.label_id, t.label_name) for t in message.threads])
            if time.monotonic() > end:
                break
    labels = {label for threads in seen for label in threads}
    assert {("prog", 3, "MoveJ"), ("prog", 4, "Waypoint_1")} <= labels
    assert {("Thread_1", 7, "Thread_1"), ("Thread_1", 8, "Wait: 0.3")} <= labels
    assert all(len(threads) == 2 for threads in seen)
    assert all(a != b for a, b in itertools.pairwise(seen))  # sent when a label changed
