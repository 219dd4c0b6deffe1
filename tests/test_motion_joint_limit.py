"""A joint reaching its position limit (issue 20.3/20.5): the arm stops at the limit, a protective
stop and a runtime exception, seen on RTDE, the primary port, the real-time port and the
dashboard; the same from a scenario's `joint_limit` fault. Real sockets; RTDE and real-time
messages unpacked with struct here (the guide: safety mode at double 102, q actual at 32-37).
"""

from __future__ import annotations

import itertools
import math
import socket
import struct
import threading
import time
from pathlib import Path

import pytest

from rtde_spec._generated import rtde_models as gen
from rtde_spec.emulator.controller.scenario import load_scenario
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.primary.codec import PrimaryStreamDecoder

PROTECTIVE_STOP = 3  # SafetyMode and SafetyStatus, both guides
LIMIT = 2 * math.pi  # the UR5e's wrist 3 (spec/arms)


def primary_messages(port: int, seconds: float, out: list[object]) -> None:
    decoder = PrimaryStreamDecoder()
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            out += [m for _, m in decoder.feed(sock.recv(65536))]


def realtime_messages(port: int, seconds: float, out: list[tuple[float, ...]]) -> None:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        buf = b""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            buf += sock.recv(65536)
            while len(buf) >= 4 and len(buf) >= struct.unpack_from(">i", buf)[0]:
                size = struct.unpack_from(">i", buf)[0]
                out.append(struct.unpack_from(f">{(size - 4) // 8}d", buf, 4))
                buf = buf[size:]


def rtde_now(port: int) -> tuple[float, ...]:
    """safety_mode, safety_status, then actual_q: one data package, parsed with struct."""
    names = ["safety_mode", "safety_status", "actual_q"]
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        sock.sendall(
            gen.RequestProtocolVersion(protocol_version=2).to_bytes()
            + gen.SetupOutputsV2(output_frequency=10.0, variable_names=names).to_bytes()
            + gen.Start().to_bytes()
        )
        buf = b""
        while True:
            buf += sock.recv(65536)
            while len(buf) >= 3 and len(buf) >= struct.unpack_from(">H", buf)[0]:
                size, kind = struct.unpack_from(">HB", buf)
                if kind == gen.DataPackage.PACKAGE_TYPE:
                    return struct.unpack_from(">ii6d", buf, 4)
                buf = buf[size:]


def dashboard(port: int, command: str) -> str:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        reader = sock.makefile("r")
        reader.readline()  # greeting
        sock.sendall(command.encode() + b"\n")
        return reader.readline().strip()


def config(**kw: object) -> EmulatorConfig:
    cfg = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=0, realtime_port=0, dashboard_port=0, **kw
    )  # type: ignore[arg-type]
    cfg.skip_after = None
    return cfg


def watch(emu: EmulatorThread, seconds: float) -> tuple[list[object], list[tuple[float, ...]]]:
    primary: list[object] = []
    realtime: list[tuple[float, ...]] = []
    readers = [
        threading.Thread(target=primary_messages, args=(emu.ports["primary"], seconds, primary)),
        threading.Thread(target=realtime_messages, args=(emu.ports["realtime"], seconds, realtime)),
    ]
    for r in readers:
        r.start()
    for r in readers:
        r.join(seconds + 20)
    return primary, realtime


@pytest.mark.slow  # seconds of real time (recording, a 5 s rule, a move): CI runs it
def test_a_speedj_into_a_joint_limit_stops_there_with_a_protective_stop_everywhere() -> None:
    with EmulatorThread(config()) as emu:
        with socket.create_connection(("127.0.0.1", emu.ports["primary"])) as sock:
            time.sleep(0.2)
            sock.sendall(b'def spin():\n  speedj([0, 0, 0, 0, 0, 3.14], 10, 10)\n  textmsg("past")\nend\n')
            primary, realtime = watch(emu, 4.0)
        safety_mode, safety_status, *q = rtde_now(emu.ports["rtde"])
        assert (safety_mode, safety_status) == (PROTECTIVE_STOP, PROTECTIVE_STOP)
        assert q[5] == pytest.approx(LIMIT, abs=1e-12)
        assert "PROTECTIVE_STOP" in dashboard(emu.ports["dashboard"], "safetystatus")
    exceptions = [m for m in primary if getattr(m, "NAME", "") == "runtime_exception_message"]
    assert len(exceptions) == 1
    text = exceptions[0].runtime_exception_text_message  # type: ignore[attr-defined]
    assert "Joint 5 position limit violated" in text and exceptions[0].script_line_number == 2  # type: ignore[attr-defined]
    assert PROTECTIVE_STOP in [getattr(m, "safety_mode_type", None) for m in primary]
    wrist = [m[36] for m in realtime]  # q actual of joint 5: guide column 37
    assert max(wrist) == pytest.approx(LIMIT, abs=1e-12)  # never past it
    assert all(b >= a for a, b in itertools.pairwise(wrist))  # up to the limit, then stands
    assert realtime[-1][101] == PROTECTIVE_STOP  # safety mode: guide column 102
    assert realtime[0][101] == 1  # NORMAL before


def test_a_scenario_joint_limit_fault_reaches_every_interface(tmp_path: Path) -> None:
    path = tmp_path / "limit.yaml"
    path.write_text("controller: 5.15.0\nfaults:\n  - {at: 1.0, fault: joint_limit, joint: 1}\n")
    with EmulatorThread(config(scenario=load_scenario(path))) as emu:
        primary, realtime = watch(emu, 2.5)
        safety_mode, _, *q = rtde_now(emu.ports["rtde"])
        assert "PROTECTIVE_STOP" in dashboard(emu.ports["dashboard"], "safetystatus")
    assert safety_mode == PROTECTIVE_STOP
    assert q[1] == pytest.approx(-LIMIT)  # from -1.5708 the nearer limit is the lower one
    texts = [
        m.runtime_exception_text_message
        for m in primary
        if getattr(m, "NAME", "") == "runtime_exception_message"
    ]  # type: ignore[attr-defined]
    assert texts and "Joint 1 position limit violated" in texts[0]
    modes = [m[101] for m in realtime]
    assert modes[0] == 1 and modes[-1] == PROTECTIVE_STOP
    stop_at = next(m[0] for m in realtime if m[101] == PROTECTIVE_STOP)
    assert stop_at == pytest.approx(1.0, abs=0.005)  # at the scenario's controller time
