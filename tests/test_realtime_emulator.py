"""The emulator's real-time ports: python-urx's real-time monitor, the version's layout at the
control rate, URScript on 30003, nothing run from the read-only port, the per-client limits.

Messages are read here with a hand-written struct loop over the guide's sizes, and with
python-urx (its URRTMonitor reads the first 692 bytes of a CB3 message: q at double 31, TCP
force at 67, getTCF at 73). urx's ports are fixed (30002, 30003), so its test has a loopback
address of its own.
"""

from __future__ import annotations

import socket
import struct
import time

import numpy as np
import pytest

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.controller.model import HOME_Q
from rtde_spec.emulator.ports.guard import ClientLimits
from rtde_spec.metamodel.arms import arm_model

urx = pytest.importorskip("urx", reason="python-urx is installed by the test extra")
pytestmark = pytest.mark.fixed_ports("127.0.0.25")  # in turn with other runs (tests/fixed_ports.py)

TARGET = [0.3, -1.4, 1.4, -1.6, -1.5, 0.2]


def read_messages(sock: socket.socket, seconds: float) -> list[tuple[float, ...]]:
    """Whole messages for `seconds`, each as its doubles (struct by hand: size, then doubles)."""
    sock.settimeout(2)
    buf = b""
    out = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        buf += sock.recv(65536)
        while len(buf) >= 4:
            (size,) = struct.unpack_from(">i", buf)
            if len(buf) < size:
                break
            out.append(struct.unpack_from(f">{(size - 4) // 8}d", buf, 4))
            buf = buf[size:]
    return out


def config(host: str, version: str, **kw: object) -> EmulatorConfig:
    off: dict[str, object] = {"realtime_port": None, "dashboard_port": None}
    return EmulatorConfig(
        host=host, rtde_port=None, primary_port=None, secondary_port=None, controller=version, **{**off, **kw}
    )  # type: ignore[arg-type]


def test_urx_real_time_monitor_follows_the_model_through_a_move() -> None:
    host = "127.0.0.25"
    cfg = config(host, "3.15.0", arm="UR5")
    cfg.secondary_port, cfg.realtime_port = 30002, 30003
    with EmulatorThread(cfg) as emu:
        socket.create_connection((host, 30003), timeout=5).close()  # served (urx would wait forever)
        robot = urx.Robot(host, use_rt=True)
        try:
            rt = robot.rtmon
            assert rt.q_actual(wait=True) == pytest.approx(HOME_Q, abs=1e-9)
            home = kin.forward(arm_model("UR5"), HOME_Q)
            assert rt.getTCF(wait=True) == pytest.approx(home, abs=1e-9)  # the tool vector (target)
            assert list(robot.get_tcp_force(wait=True)) == [0.0] * 6
            rt.start_buffering()
            robot.movej(TARGET, acc=1.4, vel=1.0, wait=True)
            rt.stop_buffering()
            assert rt.q_actual(wait=True) == pytest.approx(TARGET, abs=1e-6)
            assert rt.q_actual(wait=True) == pytest.approx(emu.model.values["actual_q"], abs=1e-9)
            assert rt.getTCF(wait=True) == pytest.approx(kin.forward(arm_model("UR5"), TARGET), abs=1e-6)
            seen = [np.asarray(q) for _, _, _, q in rt.get_buffer()]
            moving = [q for q in seen if not np.allclose(q, HOME_Q) and not np.allclose(q, TARGET)]
            assert len(moving) >= 20  # the move at 125 Hz, not a jump
            stamps = [float(c) for _, c, _, _ in rt.get_buffer()]
            assert np.diff(stamps) == pytest.approx(np.full(len(stamps) - 1, 1 / 125), abs=1e-9)
        finally:
            robot.close()
            # urx's monitor stops at its next message, which has to come before the emulator closes:
            # at the end of the stream it calls recv() for ever (b"" each time), a core and the GIL of
            # this test process for every test after this one (132 s of CPU in one whole run)
            robot.rtmon.join(timeout=5)
    assert not robot.rtmon.is_alive(), "urx's real-time monitor thread still runs"


@pytest.mark.parametrize(
    ("version", "size", "hz"), [("3.1.0", 1044, 125), ("5.4.0", 1116, 500), ("5.10.0", 1220, 500)]
)
def test_each_version_streams_its_size_at_its_control_rate(version: str, size: int, hz: int) -> None:
    host = "127.0.0.1"
    with EmulatorThread(config(host, version, realtime_port=0)) as emu:
        with socket.create_connection((host, emu.ports["realtime"])) as sock:
            messages = read_messages(sock, 1.0)
    assert {len(m) * 8 + 4 for m in messages} == {size}
    stamps = np.array([m[0] for m in messages])
    assert np.diff(stamps) == pytest.approx(np.full(len(stamps) - 1, 1 / hz), abs=1e-9)  # every step
    assert len(messages) > 0.5 * hz  # about a second's worth, on a loaded machine too
    assert messages[-1][31:37] == pytest.approx(HOME_Q)  # q actual, guide columns 32-37
    assert messages[-1][94] == 7  # robot mode RUNNING, guide column 95


@pytest.mark.slow  # seconds of a move: CI runs it
def test_urscript_on_30003_moves_the_arm_and_the_read_only_port_runs_nothing() -> None:
    host = "127.0.0.1"
    with EmulatorThread(config(host, "5.10.0", realtime_port=0, realtime_read_only_port=0)) as emu:
        with socket.create_connection((host, emu.ports["realtime_read_only"])) as ro:
            ro.sendall(f"movej({TARGET}, a=1.4, v=1.05)\n".encode())
            read_messages(ro, 0.5)
            assert emu.call(lambda: emu.model.values["actual_q"]) == pytest.approx(HOME_Q)
        with socket.create_connection((host, emu.ports["realtime"])) as sock:
            sock.sendall(f"def move():\n  movej({TARGET}, a=1.4, v=1.05)\nend\n".encode())
            messages = read_messages(sock, 3.0)
    q = np.array([m[31:37] for m in messages])
    assert q[-1] == pytest.approx(TARGET, abs=1e-9)
    progress = np.linalg.norm(q - q[0], axis=1)
    assert np.all(np.diff(progress) >= -1e-9)  # one way, along the movej
    assert np.count_nonzero((progress > 1e-6) & (progress < progress[-1] - 1e-6)) > 100  # at 500 Hz
    assert any(port == emu.ports["realtime"] for port, _ in emu.emulator.primary.scripts)


def test_a_client_over_the_limits_is_dropped_and_the_others_keep_streaming() -> None:
    host = "127.0.0.1"
    cfg = config(host, "5.10.0", realtime_port=0, limits=ClientLimits(max_input_bytes=4096, max_clients=2))
    with EmulatorThread(cfg) as emu:
        port = emu.ports["realtime"]
        with socket.create_connection((host, port)) as good, socket.create_connection((host, port)) as bad:
            # the third first: once `bad` is dropped, a third client is no longer over the limit
            with socket.create_connection((host, port)) as third:  # over max_clients: closed at once
                third.settimeout(2)
                assert third.recv(10) == b""
            bad.sendall(b"def endless():\n" + b"  textmsg(1)\n" * 1000)  # no `end`: never whole
            time.sleep(0.5)
            bad.settimeout(2)
            with pytest.raises((ConnectionResetError, BrokenPipeError)):
                while bad.recv(65536):
                    pass
                raise ConnectionResetError
            assert len(read_messages(good, 0.5)) > 100
        assert emu.emulator.clients["realtime"].dropped == 1
