"""The plain commands drivers send to the script ports act on the robot (issue 26, point 4).

UR's C++ client library (URCL, src/primary/primary_client.cpp) sends `power off`, `power on`,
`set robotmode run`, `set unlock protective stop` and `stop program` to the primary port as
lines of their own and then watches the Robot State; a controller acts on them and never
answers them with a URScript error. Each test talks to the emulator over real sockets.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable

import pytest

from rtde_spec._generated.enums import ReportLevel, RobotMode, SafetyMode
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.primary.codec import PrimaryStreamDecoder
from rtde_spec.wire.primary_base import RobotStateMessage


def serve() -> EmulatorThread:
    return EmulatorThread(
        EmulatorConfig(
            rtde_port=None,
            primary_port=0,
            secondary_port=0,
            realtime_port=0,
            controller="5.15.0",
            dashboard_port=None,
        )
    ).start()


class Primary:
    """A client of the primary port: sends lines, reads messages as they come."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.decoder = PrimaryStreamDecoder()
        self.seen: list[object] = []

    def send(self, line: str) -> None:
        self.sock.sendall(line.encode() + b"\n")

    def wait_state(
        self, test: Callable[[RobotStateMessage], bool], seconds: float = 3.0
    ) -> RobotStateMessage:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            for _, message in self.decoder.feed(self.sock.recv(65536)):
                self.seen.append(message)
                if isinstance(message, RobotStateMessage) and test(message):
                    return message
        raise AssertionError("the Robot State never showed it")

    def errors(self) -> list[str]:
        return [
            str(getattr(m, "runtime_exception_text_message", ""))
            for m in self.seen
            if getattr(m, "NAME", "") == "runtime_exception_message"
        ]

    def close(self) -> None:
        self.sock.close()


def mode(state: RobotStateMessage) -> int:
    return int(state["robot_mode_data"].robot_mode)


def test_urcls_power_cycle_on_the_primary_port_moves_the_robot_mode_without_a_script_error() -> None:
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        client.send("power off")
        client.wait_state(lambda s: mode(s) == RobotMode.POWER_OFF)
        assert emu.call(lambda: emu.model.robot_mode) == RobotMode.POWER_OFF  # the model the dashboard drives
        client.send("brake release")  # brakes stay on while powered off
        client.send("power on")
        client.wait_state(lambda s: mode(s) == RobotMode.IDLE)
        client.send("set robotmode run")
        client.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        client.send("power off")
        client.wait_state(lambda s: mode(s) == RobotMode.POWER_OFF)
        # from power off too, as URCL's tests against URSim expect (tests/test_primary_client.cpp)
        client.send("set robotmode run")
        client.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        time.sleep(0.3)
        client.wait_state(lambda s: True)
        assert client.errors() == []
    finally:
        client.close()
        emu.stop()


def test_unlock_protective_stop_and_stop_program_on_the_primary_port() -> None:
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.send("def spin():\n  while True:\n    sleep(0.1)\n  end\nend")
        client.wait_state(lambda s: s["robot_mode_data"].is_program_running)
        client.send("stop program")
        client.wait_state(lambda s: not s["robot_mode_data"].is_program_running)
        emu.call(emu.model.protective_stop)
        client.wait_state(lambda s: s["robot_mode_data"].is_protective_stopped)
        client.send("set unlock protective stop")
        state = client.wait_state(lambda s: not s["robot_mode_data"].is_protective_stopped)
        assert state["masterboard_data"].safety_mode == SafetyMode.NORMAL
        assert client.errors() == []
    finally:
        client.close()
        emu.stop()


@pytest.mark.parametrize("port", ["secondary", "realtime"])
def test_the_secondary_and_real_time_ports_take_them_too(port: str) -> None:
    emu = serve()
    watcher = Primary(emu.ports["primary"])
    try:
        with socket.create_connection(("127.0.0.1", emu.ports[port]), timeout=5) as sock:
            sock.sendall(b"power off  # a comment after the command\n")
            watcher.wait_state(lambda s: mode(s) == RobotMode.POWER_OFF)
            sock.sendall(b"power on\nbrake release\n")
            watcher.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        assert watcher.errors() == []
    finally:
        watcher.close()
        emu.stop()


def test_commands_beside_urscript_lines_run_and_the_urscript_still_runs() -> None:
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.send('close popup\nclose safety popup\ntextmsg("after the commands")')
        client.wait_state(
            lambda s: any(getattr(m, "text_message", "") == "after the commands" for m in client.seen)
        )
        client.send("power of")  # not a command: URScript, and the controller's error for it
        deadline = time.monotonic() + 3
        while not client.errors() and time.monotonic() < deadline:
            client.wait_state(lambda s: True)
        assert client.errors() and mode(client.wait_state(lambda s: True)) == RobotMode.RUNNING
    finally:
        client.close()
        emu.stop()


def test_pause_program_and_resume_program_on_the_primary_port() -> None:
    """UnderAutomation's Universal Robots SDK (PyPI underautomation_universalrobots 9.4.0.1,
    primary_interface.commands.pause_program / resume_program) sends `pause program` and
    `resume program`, one line each, on port 30001, as the older ROS driver does
    (ros-industrial/universal_robot ur_driver/src/ur_driver/driver.py, RobotCommands); the
    emulator ran them as URScript and answered a syntax error, the program going on."""
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.send("def spin():\n  while True:\n    sleep(0.1)\n  end\nend")
        client.wait_state(lambda s: s["robot_mode_data"].is_program_running)
        client.send("resume program")  # nothing paused: no effect
        client.send("pause program")
        state = client.wait_state(lambda s: s["robot_mode_data"].is_program_paused)
        assert not state["robot_mode_data"].is_program_running
        client.send("resume program")
        state = client.wait_state(lambda s: s["robot_mode_data"].is_program_running)
        assert not state["robot_mode_data"].is_program_paused
        client.send("stop program")
        client.wait_state(lambda s: not s["robot_mode_data"].is_program_running)
        assert client.errors() == []
    finally:
        client.close()
        emu.stop()


def test_set_sim_and_set_real_switch_the_real_arm_off_and_on() -> None:
    """python-urx (urx/urrobot.py URRobot.set_simulation) sends `set sim` / `set real` as a program
    on the secondary port, and UnderAutomation's SDK 9.4 (commands.set_simulated / set_real) on
    30001; the emulator ran them as URScript and answered a syntax error. Robot Mode Data's
    isRealRobotEnabled is false while simulating; the program still runs."""
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        assert client.wait_state(lambda s: True)["robot_mode_data"].is_real_robot_enabled
        with socket.create_connection(("127.0.0.1", emu.ports["secondary"]), timeout=5) as sock:
            sock.sendall(b"set sim\n")
            client.wait_state(lambda s: not s["robot_mode_data"].is_real_robot_enabled)
            sock.sendall(b'textmsg("simulated")\n')
            client.wait_state(
                lambda s: any(getattr(m, "text_message", "") == "simulated" for m in client.seen)
            )
        client.send("set real")
        state = client.wait_state(lambda s: s["robot_mode_data"].is_real_robot_enabled)
        assert state["robot_mode_data"].is_real_robot_connected
        assert client.errors() == []
    finally:
        client.close()
        emu.stop()


def test_an_unknown_name_is_reported_as_urcls_tests_expect_of_ursim() -> None:
    """URCL's test_program_execution_reports_exception (tests/test_primary_client.cpp:428-456) sends
    `calldoesntexist()` in a def on the primary port and expects the Runtime Exception message at
    line 2, column 3 with the text "compile_error_name_not_found:calldoesntexist:", the closing colon
    included, as robots send it too ("compile_error_name_not_found:get_tcp_pose:"). It lacked the colon."""
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        client.send("def illegal_fun():\n  calldoesntexist()\nend")
        deadline = time.monotonic() + 3.0
        while not client.errors() and time.monotonic() < deadline:
            client.wait_state(lambda s: True)
        seen = [m for m in client.seen if getattr(m, "NAME", "") == "runtime_exception_message"]
        where = [
            (e.script_line_number, e.script_column_number, e.runtime_exception_text_message) for e in seen
        ]
        assert where == [(2, 3, "compile_error_name_not_found:calldoesntexist:")]
    finally:
        client.close()
        emu.stop()


def test_a_scripts_protective_stop_reports_error_code_c209a0_as_a_warning() -> None:
    """URCL's read_error_code (tests/test_ur_driver.cpp:306-324) sends `sec setup(): protective_stop()`
    and waits, in a loop with no time-out, for exactly one Error Code message: code 209, argument 0
    ('A protective stop was triggered', UR's error code C209); its sendScriptBlocking tests call
    that a 'warning level error code' (tests/test_primary_client.cpp:584). None was sent: URCL's
    driver test hung there and sendScriptBlocking reported success for protective_stop()."""
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        client.send("sec setup():\n protective_stop()\nend")
        client.wait_state(lambda s: s["robot_mode_data"].is_protective_stopped)
        for _ in range(3):  # the messages of the stop come with the next Robot States
            client.wait_state(lambda s: True)
        codes = [m for m in client.seen if getattr(m, "NAME", "") == "robot_comm_message"]
        got = [(m.robot_message_code, m.robot_message_argument, m.robot_message_report_level) for m in codes]
        assert got == [(209, 0, ReportLevel.WARNING)]
    finally:
        client.close()
        emu.stop()


def test_a_move_out_of_reach_is_a_protective_stop_not_a_runtime_exception() -> None:
    """URCL's tests against URSim: an impossible movel 'will trigger a warning and protective stop'
    (tests/test_primary_client.cpp:557-560, then unlocks it), and its instruction executor waits for
    isRobotProtectiveStopped after a movel to an unreachable pose (tests/test_instruction_executor.cpp
    317-335, looping until it comes). The emulator ended the program with a runtime exception
    ('inverse kinematics failed on the way') and never stopped: URCL's test looped for ever."""
    emu = serve()
    client = Primary(emu.ports["primary"])
    try:
        client.wait_state(lambda s: mode(s) == RobotMode.RUNNING)
        client.send("def reach():\n  movel(p[10,0,0,0,0,0])\nend")
        state = client.wait_state(lambda s: s["robot_mode_data"].is_protective_stopped, seconds=12.0)
        assert state["robot_mode_data"].is_program_paused  # paused, as by any protective stop
        assert client.errors() == []
    finally:
        client.close()
        emu.stop()
