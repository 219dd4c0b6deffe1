"""Byte fidelity to a real controller where drivers look (issue 26, point 5).

- Key messages: UR's C++ client library (URCL, src/primary/robot_message/key_message.cpp)
  reads code, argument, a uint8-prefixed title and then the text to the end of the message,
  and waits for PROGRAM_XXX_STARTED with exactly the program's name.
- Kinematics Info: URCL's calibration example calls an arm calibrated when
  calibration_status is 2 (linearised); URSim 5.8 reports 0 with all-ones checksums.
- Dashboard: every command URCL's e-Series/CB3 client sends (dashboard_client_implementation_g5.cpp)
  gets a reply its pattern accepts; `isProgramSaved` is `true NAME.urp` and `running` is
  `Program running: false` on e-Series and CB3 alike (URCL's patterns, which its integration
  tests hold URSim CB3 3.14.3 to as well).
Real sockets on 127.0.0.1 throughout; the patterns below are written from those clients' checks.
"""

from __future__ import annotations

import re
import socket
import struct
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec.emulator.controller.scenario import Scenario
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.primary.codec import PrimaryStreamDecoder
from rtde_spec.wire.primary_base import RobotStateMessage


def raw_messages(sock: socket.socket, seconds: float) -> Iterator[bytes]:
    """Whole primary-port messages as they arrive, for `seconds`."""
    buf = bytearray()
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        chunk = sock.recv(65536)
        assert chunk, "closed early"
        buf += chunk
        while len(buf) >= 4 and len(buf) >= struct.unpack_from(">I", buf)[0]:
            size = struct.unpack_from(">I", buf)[0]
            yield bytes(buf[:size])
            del buf[:size]


def urcl_key_message(message: bytes) -> tuple[str, str] | None:
    """(title, text) read as URCL reads a key message: title with a uint8 length, text to the end."""
    if message[4] != 20 or message[14] != 7:  # robot message, key message
        return None
    pos = 15 + 8  # after code and argument (uint32 each)
    title_len = message[pos]
    title = message[pos + 1 : pos + 1 + title_len].decode()
    return title, message[pos + 1 + title_len :].decode()


def test_program_started_and_stopped_key_messages_carry_the_name_as_urcl_reads_it() -> None:
    config = EmulatorConfig(
        rtde_port=None,
        primary_port=0,
        secondary_port=None,
        controller="5.15.0",
        realtime_port=None,
        dashboard_port=None,
    )
    with EmulatorThread(config) as emu:
        with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as sock:
            sock.sendall(b'def urcl_script():\n  textmsg("hi")\nend\n')
            keys: list[tuple[str, str]] = []
            decoder = PrimaryStreamDecoder()
            decoded = []
            for message in raw_messages(sock, 3):
                key = urcl_key_message(message)
                if key is not None:
                    keys.append(key)
                    decoded += [m for _, m in decoder.feed(message)]
                if len(keys) == 2:
                    break
    assert keys == [("PROGRAM_XXX_STARTED", "urcl_script"), ("PROGRAM_XXX_STOPPED", "urcl_script")]
    assert [m.key_text_message for m in decoded] == ["urcl_script"] * 2  # type: ignore[attr-defined]


@pytest.mark.parametrize(("calibrated", "status"), [(True, 2), (False, 0)])
def test_kinematics_info_reports_a_calibrated_arm_unless_the_scenario_says_not(
    calibrated: bool, status: int
) -> None:
    config = EmulatorConfig(
        rtde_port=None,
        primary_port=None,
        secondary_port=0,
        scenario=Scenario(controller="5.8.0", calibrated=calibrated),
        realtime_port=None,
        dashboard_port=None,
    )
    with EmulatorThread(config) as emu:
        with socket.create_connection(("127.0.0.1", emu.ports["secondary"]), timeout=5) as sock:
            messages = raw_messages(sock, 3)
            got = [next(messages), next(messages)]
    state = PrimaryStreamDecoder().feed(b"".join(got))[1][1]
    assert isinstance(state, RobotStateMessage)
    kinematics = state["kinematics_info"]
    assert kinematics.calibration_status == status
    if not calibrated:  # as URSim 5.8 reports it
        assert tuple(kinematics.checksum) == (0xFFFFFFFF,) * 6


# command -> the pattern URCL's client accepts for its reply (whole reply), e-Series 5.15
URCL_E_SERIES = {
    "load prog.urp": r"Loading program: .*prog\.urp.*",
    "load installation default.installation": r"Loading installation: .*default\.installation.*",
    "programState": r"STOPPED prog\.urp",
    "isProgramSaved": r"(false|true) (.*\.urp)",
    "running": r"Program running: (true|false)",
    "is in remote control": r"(true|false)",
    "set operational mode AUTOMATIC": r"Operational mode .*AUTOMATIC.*",
    "get operational mode": r"AUTOMATIC",
    "clear operational mode": r"No longer controlling the operational mode\..*",
    "generate flight report": r"Flight Report generated with id:.*",
    "generate support file .": r"Completed successfully:.*",
    "saveLog": r"Log saved to disk",
    "close popup": r"closing popup",
    "close safety popup": r"closing safety popup",
    "get serial number": r"20.*",
    "get robot model": r"UR.*",
    "PolyscopeVersion": r"URSoftware .*",
    "version": r"\d\.\d+\.\d+\.\d+",
    "safetystatus": r"Safetystatus: .*",
}


class Dashboard:
    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.file = self.sock.makefile("rb")
        self.greeting = self.file.readline()

    def ask(self, command: str) -> str:
        self.sock.sendall(command.encode() + b"\n")
        return self.file.readline().decode().rstrip("\n")

    def close(self) -> None:
        self.file.close()
        self.sock.close()


def dashboard_emulator(tmp_path: Path, version: str) -> EmulatorThread:
    programs = tmp_path / "programs"
    programs.mkdir()
    (programs / "prog.script").write_text("def prog():\n  sleep(30)\nend\n")
    (programs / "prog.urp").write_bytes(b"\x1f\x8b")
    (programs / "default.installation").write_bytes(b"\x1f\x8b")
    config = EmulatorConfig(
        rtde_port=None,
        primary_port=None,
        secondary_port=None,
        dashboard_port=0,
        programs=programs,
        controller=version,
        realtime_port=None,
    )
    return EmulatorThread(config).start()


def test_every_command_urcls_dashboard_client_sends_gets_a_reply_it_accepts(tmp_path: Path) -> None:
    emu = dashboard_emulator(tmp_path, "5.15.0")
    dash = Dashboard(emu.ports["dashboard"])
    try:
        for command, pattern in URCL_E_SERIES.items():
            reply = dash.ask(command)
            assert re.fullmatch(pattern, reply), (command, reply)
        assert dash.ask("get operational mode") == "NONE"  # cleared above, as URSim answers
        assert dash.ask("set operational mode sideways").startswith("Failed")
        assert dash.ask("load installation missing.installation") == "File not found: missing.installation"
        assert dash.ask("setUserRole programmer").startswith("could not understand")  # CB3 only
    finally:
        dash.close()
        emu.stop()


def test_cb3_says_true_in_lower_case_as_urcl_expects_of_it_and_knows_user_roles(tmp_path: Path) -> None:
    emu = dashboard_emulator(tmp_path, "3.15.8")
    dash = Dashboard(emu.ports["dashboard"])
    try:
        assert dash.ask("load prog.urp") == "Loading program: prog.urp"
        assert dash.ask("isProgramSaved") == "true prog.urp"
        assert dash.ask("running") == "Program running: false"
        assert dash.ask("setUserRole operator") == "Setting user role: operator"
        assert dash.ask("getUserRole") == "OPERATOR"
        assert dash.ask("setUserRole admin") == "Failed setting user role: admin"
        assert dash.ask("saveLog") == "Log saved to disk"
        assert dash.ask("get operational mode").startswith("could not understand")  # e-Series only
    finally:
        dash.close()
        emu.stop()


def test_ur_rtde_is_program_saved_on_a_cb3_says_false_as_it_would_of_ursim(tmp_path: Path) -> None:
    """ur_rtde looks for "True", which a CB3 3.14 does not say (URCL's tests hold it to lower case)."""
    dashboard_client = pytest.importorskip("dashboard_client", reason="ur_rtde is not installed")
    emu = dashboard_emulator(tmp_path, "3.15.8")
    client = dashboard_client.DashboardClient("127.0.0.1", emu.ports["dashboard"])
    try:
        client.connect()
        client.loadURP("prog.urp")
        assert client.isProgramSaved() is False
    finally:
        client.disconnect()
        emu.stop()
