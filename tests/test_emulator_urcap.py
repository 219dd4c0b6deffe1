"""The ROS driver's mode that is not headless: a program with the External Control URCap node,
loaded and played on the dashboard. When played, the emulator asks the driver for its program
(`request_program` on the driver's script sender, port 50002), puts the part between
`# HEADER_BEGIN` and `# HEADER_END` on top and the rest at the node, and runs it, as PolyScope
with the URCap does. The .urp here is the shape of the one UR's client library tests with."""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.rtde.client import RtdeClient

DRIVER_HOST = "127.0.0.76"  # the driver's own loopback address: its script sender on the usual 50002
pytestmark = pytest.mark.fixed_ports(DRIVER_HOST)

URP = """<URProgram name="external_control" installation="default" createdIn="5.17.2">
  <kinematics status="NOT_INITIALIZED" validChecksum="false">
    <a value="0.0, -0.425, -0.3922, 0.0, 0.0, 0.0"/>
  </kinematics>
  <children>
    <InitVariablesNode/>
    <MainProgram runOnlyOnce="true" InitVariablesNode="true">
      <children>
        <Contributed strategyClass="com.fzi.externalcontrol.ExternalControlNode"
                     strategyProgramNodeType="External Control"
                     strategyURCapDeveloper="FZI Research Center for Information Technology"
                     strategyURCapName="External Control">
          <dataModel/>
        </Contributed>
      </children>
    </MainProgram>
  </children>
</URProgram>
"""

DRIVER_PROGRAM = """# HEADER_BEGIN
global answer_value = 42
def answer():
  return answer_value
end
# HEADER_END

# NODE_CONTROL_LOOP_BEGINS
write_output_integer_register(0, answer())
sleep(30)
# NODE_CONTROL_LOOP_ENDS
"""


def script_sender(host: str, port: int = 0) -> tuple[socket.socket, list[bytes]]:
    """A driver's script sender: answers `request_program` with its program (URCL's ScriptSender)."""
    server = socket.create_server((host, port))
    requests: list[bytes] = []

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            with conn:
                requests.append(conn.recv(100))
                conn.sendall(DRIVER_PROGRAM.encode())

    threading.Thread(target=serve, daemon=True).start()
    return server, requests


def dashboard(port: int, source: str = "127.0.0.1") -> tuple[socket.socket, object]:
    sock = socket.create_connection(("127.0.0.1", port), timeout=5, source_address=(source, 0))
    reader = sock.makefile("rb")
    reader.readline()
    return sock, reader


def ask(sock: socket.socket, reader: object, command: str) -> str:
    sock.sendall(command.encode() + b"\n")
    return reader.readline().decode().strip()  # type: ignore[attr-defined, no-any-return]


def emulator(tmp_path: Path, external_control: str | None) -> EmulatorThread:
    programs = tmp_path / "programs"
    programs.mkdir()
    (programs / "external_control.urp").write_text(URP)
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=0, dashboard_port=0, realtime_port=None,
        programs=programs, external_control=external_control,
    )  # fmt: skip
    return EmulatorThread(config).start()


def register_0(emu: EmulatorThread, seconds: float = 10.0) -> int:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        client.setup_outputs(["output_int_register_0"], 10)
        client.start()
        deadline = time.monotonic() + seconds
        while (value := client.receive(2).output_int_register_0) != 42 and time.monotonic() < deadline:
            pass
        return int(value)


@pytest.fixture
def driver() -> Iterator[tuple[socket.socket, list[bytes]]]:
    server, requests = script_sender("127.0.0.1")
    yield server, requests
    server.close()


def test_play_asks_the_driver_named_for_its_program_and_runs_it(
    tmp_path: Path, driver: tuple[socket.socket, list[bytes]]
) -> None:
    server, requests = driver
    emu = emulator(tmp_path, f"127.0.0.1:{server.getsockname()[1]}")
    try:
        sock, reader = dashboard(emu.ports["dashboard"])
        ask(sock, reader, "power on")
        ask(sock, reader, "brake release")
        assert ask(sock, reader, "load external_control.urp") == "Loading program: external_control.urp"
        assert ask(sock, reader, "play") == "Starting program"
        assert register_0(emu) == 42  # the header's function, called by the node's program
        assert requests == [b"request_program\n"]
        assert ask(sock, reader, "programState").startswith("PLAYING")
        sock.close()
    finally:
        emu.stop()


def test_by_default_the_driver_is_the_client_that_plays(tmp_path: Path) -> None:
    server, requests = script_sender(DRIVER_HOST, 50002)
    emu = emulator(tmp_path, None)
    try:
        sock, reader = dashboard(emu.ports["dashboard"], source=DRIVER_HOST)
        for command in ("power on", "brake release", "load external_control.urp", "play"):
            ask(sock, reader, command)
        assert register_0(emu) == 42
        assert requests == [b"request_program\n"]
        sock.close()
    finally:
        emu.stop()
        server.close()


def test_a_driver_that_is_not_there_leaves_the_program_stopped(tmp_path: Path) -> None:
    closed = socket.create_server(("127.0.0.1", 0))
    port = closed.getsockname()[1]
    closed.close()  # nothing listens there now
    emu = emulator(tmp_path, f"127.0.0.1:{port}")
    try:
        sock, reader = dashboard(emu.ports["dashboard"])
        for command in ("power on", "brake release", "load external_control.urp"):
            ask(sock, reader, command)
        assert ask(sock, reader, "play") == "Starting program"
        time.sleep(1.0)
        assert ask(sock, reader, "programState").startswith("STOPPED")
        sock.close()
    finally:
        emu.stop()
