"""Every public call of ur_rtde's DashboardClient, RTDEIOInterface and ScriptClient (pip ur_rtde)
against the emulator of an e-Series 5.x and a CB3 3.x controller.

Each call is held to what a controller answers (the reply texts of spec/dashboard/commands.yaml,
UR's "Dashboard Server" articles, the patterns UR's client library matches) and its effect is looked
for where a client sees it: ur_rtde's RTDEReceiveInterface (robot mode, runtime state, digital
outputs, speed slider, analog outputs, protective stop) and the RTDE input registers read back. The
clients run in a process of their own (tests/ur_rtde_robot.py `Clients`): every call is answered
within a deadline, or the test fails naming the call that hung.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.rtde.client import RtdeClient

from .ur_rtde_robot import ClientError, Clients, serve, settle_until

pytest.importorskip("dashboard_client", reason="ur_rtde is installed by the test extra")

E_SERIES, CB3 = "5.15.0", "3.15.8"
HOSTS = {E_SERIES: ("127.0.0.81", "UR5e"), CB3: ("127.0.0.82", "UR5")}  # ur_rtde's ports are fixed
pytestmark = [
    pytest.mark.xdist_group("ur-rtde-sweep"),
    pytest.mark.fixed_ports(*(h for h, _ in HOSTS.values())),
]
POWER_OFF, IDLE, RUNNING = 3, 5, 7  # robot_mode
STOPPED, PLAYING, PAUSED = 1, 2, 4  # runtime_state
PROGRAMS = {
    "prog.script": 'def prog():\n  textmsg("prog")\n  sleep(30)\nend\n',
    "prog.urp": "",  # PolyScope's file: the .script beside it runs
    "other.script": "def other():\n  sleep(30)\nend\n",
    "short.script": "def short():\n  set_standard_digital_out(6, True)\n  sleep(0.1)\nend\n",
    "default.installation": "",
}


@dataclass
class Robot:
    clients: Clients
    controller: str
    host: str
    log: list[str]
    folder: Path

    def dash(self, method: str, *args: Any) -> Any:
        return self.clients.call("dash", method, *args)

    def raw(self, line: str) -> str:
        """A dashboard command line through the client's own send and receive."""
        self.dash("send", line + "\n")
        return str(self.dash("receive"))

    def io(self, method: str, *args: Any) -> Any:
        return self.clients.call("io", method, *args)

    def recv(self, method: str) -> Any:
        return self.clients.call("recv", method)

    def script(self, method: str, *args: Any) -> Any:
        return self.clients.call("script", method, *args)

    @property
    def cb3(self) -> bool:
        return self.controller.startswith("3.")

    def shows(self, method: str, value: Any, what: str) -> None:
        settle_until(lambda: self.recv(method) == value, 3.0, f"{what}: {method} never gave {value!r}")

    def ready(self) -> None:
        """Powered, brakes released, no program: as each test starts."""
        self.dash("stop")
        self.dash("powerOn")
        self.dash("brakeRelease")
        self.shows("getRobotMode", RUNNING, "ready")


@pytest.fixture(scope="module", params=[E_SERIES, CB3])
def robot(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Robot]:
    controller = request.param
    host, model = HOSTS[controller]
    folder = tmp_path_factory.mktemp("programs")
    for name, text in PROGRAMS.items():
        (folder / name).write_text(text)
    (folder.parent / "outside.script").write_text(PROGRAMS["other.script"])  # a file, not a program of ours
    proc, log = serve(host, controller, model, folder)
    clients = Clients()
    try:
        clients.new("dash", "dashboard_client", "DashboardClient", host)
        clients.call("dash", "connect")
        clients.new("recv", "rtde_receive", "RTDEReceiveInterface", host)
        clients.new("io", "rtde_io", "RTDEIOInterface", host)
        major, minor = (int(p) for p in controller.split(".")[:2])
        clients.new("script", "script_client", "ScriptClient", host, major, minor)
        yield Robot(clients, controller, host, log, folder)
        for name in ("dash", "recv", "io"):  # the script client disconnects in its tests
            clients.call(name, "disconnect")
    finally:
        clients.close()
        proc.terminate()
        proc.wait(10)


def test_identity_and_status_queries(robot: Robot) -> None:
    assert robot.dash("isConnected")
    assert robot.dash("polyscopeVersion") == f"{robot.controller}.0"
    assert robot.dash("getRobotModel") == "UR5"  # the family: a UR5e says UR5
    assert robot.dash("safetymode") == "Safetymode: NORMAL"
    assert robot.dash("safetystatus") == "Safetystatus: NORMAL"
    if robot.cb3:  # ur_rtde asks neither below 5.6 (a warning, or its own exception)
        with pytest.raises(ClientError, match=r"not supported .* less than 5\.6\.0"):
            robot.dash("getSerialNumber")
        assert robot.dash("isInRemoteControl") is False
        assert robot.raw("version") == "could not understand: 'version'"
    else:
        serial = robot.dash("getSerialNumber")
        assert serial.startswith("20") and serial.isdigit()
        assert robot.dash("isInRemoteControl") is True
        assert robot.raw("version") == "5.15.0.0"


def test_power_and_brakes_show_on_rtde(robot: Robot) -> None:
    robot.ready()
    robot.dash("powerOff")
    assert robot.dash("robotmode") == "Robotmode: POWER_OFF"
    robot.shows("getRobotMode", POWER_OFF, "power off")
    robot.dash("brakeRelease")  # powers on, then releases: UR's client library's power cycle on URSim
    assert robot.dash("robotmode") == "Robotmode: RUNNING"
    robot.shows("getRobotMode", RUNNING, "brake release from power off")
    robot.dash("powerOff")
    robot.dash("powerOn")
    assert robot.dash("robotmode") == "Robotmode: IDLE"
    robot.shows("getRobotMode", IDLE, "power on")
    robot.dash("brakeRelease")
    assert robot.dash("robotmode") == "Robotmode: RUNNING"
    robot.shows("getRobotMode", RUNNING, "brake release")
    robot.dash("powerOn")  # on a released arm: it stays as it is
    assert robot.dash("robotmode") == "Robotmode: RUNNING"


def test_load_play_pause_stop_show_on_rtde(robot: Robot) -> None:
    robot.ready()
    with pytest.raises(ClientError, match=r"^RuntimeError: File not found: missing\.urp$"):
        robot.dash("loadURP", "missing.urp")
    robot.dash("loadURP", "prog.urp")
    assert robot.dash("getLoadedProgram") == "Loaded program: prog.urp"
    assert robot.raw("isProgramSaved") == "true prog.urp"  # URCL's pattern, on CB3 too
    assert robot.dash("isProgramSaved") is False  # ur_rtde looks for "True", which neither line says
    assert robot.raw("running") == "Program running: false"
    assert robot.dash("programState") == "STOPPED prog.urp" and robot.dash("running") is False
    robot.dash("play")  # raises unless the reply is exactly "Starting program"
    assert robot.dash("programState") == "PLAYING prog.urp" and robot.dash("running") is True
    robot.shows("getRuntimeState", PLAYING, "play")
    robot.dash("pause")
    assert robot.dash("programState") == "PAUSED prog.urp" and robot.dash("running") is False
    robot.shows("getRuntimeState", PAUSED, "pause")
    robot.dash("play")
    robot.dash("stop")
    assert robot.dash("programState") == "STOPPED prog.urp"
    robot.shows("getRuntimeState", STOPPED, "stop")
    with pytest.raises(ClientError, match="Failed to execute: pause"):
        robot.dash("pause")
    robot.dash("loadURP", "short.script")  # sets digital output 6 and ends by itself
    robot.dash("play")
    settle_until(lambda: robot.dash("running") is False, 3.0, "the short program never ended")
    assert robot.dash("programState") == "STOPPED short.script"
    assert robot.recv("getActualDigitalOutputBits") & 1 << 6


def test_loading_while_a_program_plays_stops_it(robot: Robot) -> None:
    robot.ready()
    robot.dash("loadURP", "prog.urp")
    robot.dash("play")
    with pytest.raises(ClientError, match="File not found"):  # a failed load leaves it playing
        robot.dash("loadURP", "missing.urp")
    assert robot.dash("programState") == "PLAYING prog.urp"
    robot.dash("loadURP", "other.script")
    assert robot.dash("programState") == "STOPPED other.script"  # UR's client library waits for it
    assert robot.dash("running") is False
    assert robot.dash("getLoadedProgram") == "Loaded program: other.script"
    robot.shows("getRuntimeState", STOPPED, "the program that played")
    robot.dash("play")
    assert robot.dash("programState") == "PLAYING other.script"
    robot.dash("stop")


def test_a_path_into_the_controllers_programs_folder_names_the_file_in_ours(robot: Robot) -> None:
    robot.ready()
    robot.dash("loadURP", "/programs/prog.urp")  # a robot's folder; URCL's tests load from URSim's
    assert robot.dash("programState") == "STOPPED prog.urp"
    robot.dash("loadURP", "/ursim/programs/other.script")
    assert robot.dash("getLoadedProgram") == "Loaded program: other.script"
    assert robot.raw("load installation /programs/default.installation").startswith("Loading installation")
    with pytest.raises(ClientError, match="File not found"):  # still nothing outside it
        robot.dash("loadURP", "/programs/../outside.script")


def test_popups_log_installation_and_roles(robot: Robot) -> None:
    for call, args in (("popup", ("hello there",)), ("closePopup", ()), ("closeSafetyPopup", ())):
        assert robot.dash(call, *args) is None
    robot.dash("addToLog", "sweep log line")
    assert robot.raw("popup again") == "showing popup"
    assert robot.raw("close popup") == "closing popup"
    assert robot.raw("addToLog a second line") == "Added log message"
    assert robot.raw("close safety popup") == "closing safety popup"
    assert robot.raw("load installation default.installation") == "Loading installation: default.installation"
    assert robot.raw("load installation none.installation") == "File not found: none.installation"
    settle_until(lambda: any("dashboard log: sweep log line" in line for line in robot.log), 3.0)
    with pytest.raises(ClientError, match="TypeError"):  # ur_rtde's Python module has no UserRole to pass
        robot.dash("setUserRole", "operator")
    if robot.cb3:  # user roles are CB3's; operational modes e-Series'
        assert robot.raw("setUserRole operator") == "Setting user role: operator"
        assert robot.raw("getUserRole") == "OPERATOR"
        assert (
            robot.raw("set operational mode manual") == "could not understand: 'set operational mode manual'"
        )
    else:
        assert robot.raw("setUserRole operator") == "could not understand: 'setUserRole operator'"
        assert robot.raw("set operational mode automatic") == "Operational mode 'automatic' is set"
        assert robot.raw("get operational mode") == "AUTOMATIC"
        assert robot.raw("clear operational mode").startswith("No longer controlling the operational mode.")
        assert robot.raw("get operational mode") == "NONE"


def test_a_protective_stop_is_refused_unlock_within_five_seconds_and_cleared_by_restart_safety(
    robot: Robot,
) -> None:
    robot.ready()
    robot.script("connect")
    assert robot.script("sendScriptCommand", "protective_stop()\n")
    robot.shows("isProtectiveStopped", True, "protective_stop()")
    assert robot.dash("safetymode") == "Safetymode: PROTECTIVE_STOP"
    assert robot.dash("safetystatus") == "Safetystatus: PROTECTIVE_STOP"
    robot.dash("closeSafetyPopup")
    with pytest.raises(
        ClientError, match="Unlock protective stop failure: Cannot unlock protective stop until 5s"
    ):
        robot.dash("unlockProtectiveStop")
    robot.dash("restartSafety")
    assert robot.dash("safetymode") == "Safetymode: NORMAL"
    assert robot.dash("robotmode") == "Robotmode: POWER_OFF"
    robot.shows("isProtectiveStopped", False, "restart safety")
    robot.shows("getRobotMode", POWER_OFF, "restart safety")
    robot.script("disconnect")


def test_io_interface_outputs_show_on_rtde(robot: Robot) -> None:
    robot.ready()
    bits = "getActualDigitalOutputBits"
    assert robot.io("isConnected")
    assert robot.io("setStandardDigitalOut", 3, True)
    settle_until(lambda: robot.recv(bits) & 1 << 3, 3.0, "standard digital output 3")
    assert robot.io("setStandardDigitalOut", 3, False)
    settle_until(lambda: not robot.recv(bits) & 1 << 3, 3.0, "standard digital output 3 off")
    assert robot.io("setConfigurableDigitalOut", 2, True)
    settle_until(lambda: robot.recv(bits) & 1 << (8 + 2), 3.0, "configurable digital output 2")
    assert robot.io("setToolDigitalOut", 1, True)
    settle_until(lambda: robot.recv(bits) & 1 << (16 + 1), 3.0, "tool digital output 1")
    assert robot.io("setSpeedSlider", 0.3)
    robot.shows("getTargetSpeedFraction", 0.3, "speed slider")
    assert robot.io("setSpeedSlider", 1.0)
    robot.shows("getTargetSpeedFraction", 1.0, "speed slider back")
    assert robot.io("setAnalogOutputVoltage", 0, 0.5)
    robot.shows("getStandardAnalogOutput0", 0.5, "analog output 0")
    assert robot.io("setAnalogOutputCurrent", 1, 0.25)
    robot.shows("getStandardAnalogOutput1", 0.25, "analog output 1")
    assert robot.io("setInputIntRegister", 18, 42)
    assert robot.io("setInputDoubleRegister", 19, 1.5)
    with pytest.raises(ClientError, match="ValueError: The supported range of setInputIntRegister"):
        robot.io("setInputIntRegister", 30, 1)  # ur_rtde's own check: 18-22 in the lower range
    with RtdeClient(robot.host, 30004) as client:  # the registers read back as outputs
        client.setup_outputs(["input_int_register_18", "input_double_register_19", "analog_io_types"], 10)
        client.start()
        record = client.receive()
    assert (record.input_int_register_18, record.input_double_register_19) == (42, 1.5)
    assert record.analog_io_types & 0b1100 == 0b0100  # output 0 in volts, output 1 in milliamperes
    robot.io("disconnect")
    assert robot.io("isConnected") is False
    assert robot.io("reconnect") and robot.io("isConnected")
    assert robot.io("setStandardDigitalOut", 0, True)
    settle_until(lambda: robot.recv(bits) & 1, 3.0, "standard digital output 0 after reconnecting")


def test_script_client_runs_what_it_sends(robot: Robot) -> None:
    robot.ready()
    bits = "getActualDigitalOutputBits"
    robot.script("disconnect")
    assert robot.script("isConnected") is False
    assert robot.script("sendScriptCommand", "set_standard_digital_out(5, True)\n") is False  # not connected
    robot.script("connect")
    assert robot.script("isConnected")
    assert robot.script("sendScriptCommand", "set_standard_digital_out(5, True)\n")
    settle_until(lambda: robot.recv(bits) & 1 << 5, 3.0, "a one-line script")
    program = robot.folder / "user.script"
    program.write_text("def user():\n  set_configurable_digital_out(4, True)\nend\n")
    assert robot.script("sendScript", str(program))
    settle_until(lambda: robot.recv(bits) & 1 << (8 + 4), 3.0, "a script file")
    assert robot.script("sendScript", str(robot.folder / "missing.script")) is False
    assert "# HEADER_BEGIN" in robot.script("getScript")  # the body of ur_rtde's own control script
    robot.script("disconnect")
    assert robot.script("isConnected") is False


def test_shutdown_powers_off_quit_closes_and_a_new_connection_is_greeted(robot: Robot) -> None:
    robot.ready()
    robot.dash("shutdown")  # the emulator powers the arm off; it does not end itself
    robot.shows("getRobotMode", POWER_OFF, "shutdown")
    assert robot.raw("quit") == "Disconnected"
    robot.dash("disconnect")
    assert robot.dash("isConnected") is False
    robot.dash("connect")  # reads the greeting
    assert robot.dash("isConnected") and robot.dash("robotmode").startswith("Robotmode: ")
