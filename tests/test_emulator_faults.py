"""Faults as scenarios (issue 20, point 5): scheduled in the scenario YAML, seen on RTDE, the primary
port and the dashboard, through real sockets."""

from __future__ import annotations

import itertools
import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from rtde_spec._generated import rtde_models as gen
from rtde_spec.emulator.controller.scenario import Scenario, load_scenario
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.errors import UsageError
from rtde_spec.primary.codec import PrimaryStreamDecoder

SCENARIO = """
controller: 5.15.0
faults:
  - {at: 1.0, fault: protective_stop}
  - {at: 1.5, fault: network_drop, seconds: 1.0}
  - {at: 3.0, fault: emergency_stop, seconds: 0.5}
"""


def record_rtde(port: int, seconds: float, rows: list[tuple[float, int, int, int]]) -> None:
    """timestamp, robot_mode, safety_mode, safety_status at 125 Hz, parsed with struct."""
    names = ["timestamp", "robot_mode", "safety_mode", "safety_status"]
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        sock.sendall(
            gen.RequestProtocolVersion(protocol_version=2).to_bytes()
            + gen.SetupOutputsV2(output_frequency=125.0, variable_names=names).to_bytes()
            + gen.Start().to_bytes()
        )
        buf = bytearray()
        deadline = time.monotonic() + seconds * 5 + 10  # a loaded machine runs the controller late
        while time.monotonic() < deadline and not (rows and rows[-1][0] >= seconds):  # controller time
            buf += sock.recv(65536)
            while len(buf) >= 3 and len(buf) >= struct.unpack_from(">H", buf)[0]:
                size, kind = struct.unpack_from(">HB", buf)
                if kind == gen.DataPackage.PACKAGE_TYPE:
                    rows.append(struct.unpack_from(">diii", buf, 4))
                del buf[:size]


def primary_safety_messages(port: int, seconds: float, out: list[int]) -> None:
    decoder = PrimaryStreamDecoder()
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        deadline = time.monotonic() + seconds * 5 + 10  # a loaded machine runs the controller late
        while time.monotonic() < deadline and len(out) < 3:
            for _, message in decoder.feed(sock.recv(65536)):
                if getattr(message, "NAME", "") == "safety_mode_message":
                    out.append(message.safety_mode_type)  # type: ignore[union-attr]


@pytest.mark.slow  # seconds of scheduled faults: CI runs it
def test_scheduled_faults_show_on_rtde_and_the_primary_port(tmp_path: Path) -> None:
    path = tmp_path / "faults.yaml"
    path.write_text(SCENARIO)
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=0,
        secondary_port=0,
        scenario=load_scenario(path),
        realtime_port=None,
        dashboard_port=None,
    )
    config.skip_after = None  # a stall of the loaded machine delays packages, never skips them
    rows: list[tuple[float, int, int, int]] = []
    safety: list[int] = []
    with EmulatorThread(config) as emu:
        readers = [
            threading.Thread(target=record_rtde, args=(emu.ports["rtde"], 4.2, rows)),
            threading.Thread(target=primary_safety_messages, args=(emu.ports["primary"], 4.2, safety)),
        ]
        for r in readers:
            r.start()
        for r in readers:
            r.join(20)
    by_time = {round(t, 3): (mode, smode, status) for t, mode, smode, status in rows}
    stamps = [t for t, *_ in rows]
    assert stamps, "no data"

    def at(t: float) -> tuple[int, int, int]:
        return by_time[min(by_time, key=lambda s: abs(s - t))]

    assert stamps[0] < 0.8 and at(0.8) == (7, 1, 1)  # RUNNING, NORMAL
    assert at(1.3)[1:] == (3, 3)  # protective stop: safety mode and status
    gaps = [(a, b) for a, b in itertools.pairwise(stamps) if b - a > 0.5]
    assert len(gaps) == 1 and 1.45 <= gaps[0][0] <= 1.5 and 2.5 <= gaps[0][1] <= 2.55  # the network drop
    assert at(3.2) == (3, 7, 7)  # emergency stop: arm powered off, ROBOT_EMERGENCY_STOP
    assert at(3.8) == (3, 1, 1)  # released after 0.5 s; the arm stays powered off
    assert safety[:3] == [3, 7, 1]  # a safety mode message for each change, on the primary port


def test_fault_entries_are_validated() -> None:
    with pytest.raises(ValueError):
        Scenario.model_validate({"faults": [{"at": 1, "fault": "meteor"}]})
    with pytest.raises(ValueError):
        Scenario.model_validate({"faults": [{"at": -1, "fault": "power_loss"}]})


def test_a_scenario_with_yaml_aliases_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "alias.yaml"
    path.write_text("controller: &v 5.15.0\nfaults: []\nx: *v\n")
    with pytest.raises(UsageError, match="alias"):
        load_scenario(path)
