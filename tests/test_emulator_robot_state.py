"""The emulator's primary ports send what a controller of the chosen version sends (issue 20, points 1 and 7).

Against URSim's layout for e-Series (URSIM_5_8_UR5E below, issue 26 point 5) and, for CB3,
against python-urx's struct formats for 3.2+ firmware, which were written against real CB3
robots independently of this spec.
"""

from __future__ import annotations

import itertools
import os
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import rtde_spec
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.metamodel.arms import arm_model
from rtde_spec.primary.codec import PrimaryStreamDecoder
from rtde_spec.wire.primary_base import RobotStateMessage


def shape(message: bytes) -> list[tuple[int, int]]:
    """(type, size) of each sub-package of a Robot State, read with struct alone."""
    out, pos = [], 5
    while pos < len(message):
        size, kind = struct.unpack_from(">IB", message, pos)
        out.append((kind, size))
        pos += size
    return out


def messages(port: int, count: int, timeout: float = 5.0) -> Iterator[bytes]:
    """The first `count` whole messages a primary/secondary port sends."""
    with socket.create_connection(("127.0.0.1", port), timeout=timeout) as sock:
        buf = bytearray()
        while count:
            while len(buf) < 4 or len(buf) < struct.unpack_from(">I", buf)[0]:
                chunk = sock.recv(65536)
                assert chunk, "closed early"
                buf += chunk
            size = struct.unpack_from(">I", buf)[0]
            yield bytes(buf[:size])
            del buf[:size]
            count -= 1


def serve(version: str) -> EmulatorThread:
    return EmulatorThread(
        EmulatorConfig(
            rtde_port=None,
            primary_port=0,
            secondary_port=0,
            controller=version,
            realtime_port=None,
            dashboard_port=None,
        )
    ).start()


def robot_states(version: str, count: int, port: str = "secondary") -> tuple[bytes, list[bytes]]:
    emu = serve(version)
    try:
        got = list(messages(emu.ports[port], count + 1))
    finally:
        emu.stop()
    return got[0], [m for m in got[1:] if m[4] == 16]


# (type, size) of each sub-package of the first Robot State a URSim 5.8 UR5e sends: the capture in UR's
# C++ client library's tests (UniversalRobots/Universal_Robots_Client_Library,
# tests/test_primary_parser.cpp, "First RobotState of UR5e from URSim v5.8"), 1,386 bytes in all
URSIM_5_8_UR5E = [
    (0, 47), (1, 251), (4, 101), (5, 225), (9, 53), (3, 75), (2, 37),
    (6, 445), (7, 61), (8, 9), (10, 43), (11, 26), (12, 8),
]  # fmt: skip
ONCE = {5, 9, 6}  # kinematics info, calibration data, configuration data: after connecting


def test_first_robot_state_of_5_8_is_ursims_sub_packages_order_and_sizes() -> None:
    first_message, states = robot_states("5.8.0", 1)
    assert shape(states[0]) == URSIM_5_8_UR5E
    assert len(states[0]) == 1386 == 5 + sum(size for _, size in URSIM_5_8_UR5E)
    decoder = PrimaryStreamDecoder()
    state = [m for _, m in decoder.feed(first_message + states[0])][1]
    assert isinstance(state, RobotStateMessage)
    assert all(not s.missing and not s.extra for s in state.sub_packages)
    assert decoder.warnings_for(state) == []


@pytest.mark.parametrize("version", ["5.23.0", "10.11.0"])
def test_later_versions_add_cumulative_runtime_data_after_ursims_layout(version: str) -> None:
    first_message, states = robot_states(version, 1)
    assert shape(states[0]) == [*URSIM_5_8_UR5E, (16, 21)]
    decoder = PrimaryStreamDecoder()
    decoded = [m for _, m in decoder.feed(first_message + states[0])]
    assert str(decoder.version) == version
    state = decoded[1]
    assert isinstance(state, RobotStateMessage)
    assert all(not s.missing and not s.extra for s in state.sub_packages)
    assert decoder.warnings_for(state) == []


def test_e_series_before_5_23_has_no_cumulative_runtime_and_later_states_only_the_periodic_ones() -> None:
    _, states = robot_states("5.15.0", 12)
    assert shape(states[0]) == URSIM_5_8_UR5E  # cumulative runtime data came in 5.23
    assert all(kind not in ONCE for s in states[1:] for kind, _ in shape(s))
    assert shape(states[1]) == [(k, n) for k, n in URSIM_5_8_UR5E if k not in ONCE]


def test_cumulative_runtime_data_once_a_second() -> None:
    _, states = robot_states("5.23.0", 21)
    with_it = [i for i, s in enumerate(states) if 16 in [k for k, _ in shape(s)]]
    assert with_it[0] == 0 and len(with_it) in (2, 3)  # the first, then one in each ten
    assert all(b - a == 10 for a, b in itertools.pairwise(with_it[1:]))


def test_cb3_layouts_match_python_urx_formats_and_its_parser() -> None:
    from urx.ursecmon import ParserUtils

    first_message, states = robot_states("3.15.8", 1)
    sizes = dict(shape(states[0]))
    # python-urx (urx/ursecmon.py), formats for firmware 3.2+: !IBQ???????BBddd, 6x dddffffB,
    # iBdddddddddddd, iBbbddfBffB, iBddddddd (sizes include the 5-byte sub-package header)
    for kind, fmt in [
        (0, "!IBQ???????BBddd"),
        (1, "!IB" + "dddffffB" * 6),
        (4, "!iBdddddddddddd"),
        (2, "!iBbbddfBffB"),
        (7, "!iBddddddd"),
    ]:
        assert sizes[kind] == struct.calcsize(fmt), kind
    assert 10 not in sizes and 11 not in sizes and 12 not in sizes  # e-Series sub-packages
    assert sizes[9] == 53  # Calibration Data: UR's 2015 workbook gives CB3 this 53-byte sub-package
    parser = ParserUtils()
    parsed = parser.parse(states[0])
    assert parser.version == (3, 2)  # told by the robot mode data's size, as on a CB3 robot
    assert parsed["RobotModeData"]["robotMode"] == 7
    assert parsed["CartesianInfo"]["tcpOffsetZ"] == 0.0
    decoder = PrimaryStreamDecoder()
    decoded = [m for _, m in decoder.feed(first_message + states[0])]
    assert str(decoder.version) == "3.15.8" and decoder.warnings_for(decoded[1]) == []


def test_kinematics_info_and_configuration_carry_the_arms_dh_parameters() -> None:
    first_message, states = robot_states("5.15.0", 1)
    state = PrimaryStreamDecoder().feed(first_message + states[0])[1][1]
    dh = arm_model("UR5e").dh
    kin, conf = state["kinematics_info"], state["configuration_data"]
    for message in (kin, conf):
        assert (
            tuple(message.dh_a) == dh.a
            and tuple(message.dh_d) == dh.d
            and tuple(message.dh_alpha) == dh.alpha
        )
    assert conf.robot_type == 1  # UR5 family
    assert len(set(kin.checksum)) == 6


def test_cartesian_info_is_the_models_tcp_pose_and_offset() -> None:
    emu = serve("5.15.0")
    try:
        emu.call(emu.model.values.__setitem__, "tcp_offset", (0.0, 0.0, 0.15, 0.0, 0.0, 0.0))
        got = list(messages(emu.ports["secondary"], 3))
        pose = emu.call(lambda: tuple(emu.model.values["actual_TCP_pose"]))  # the arm is at rest
        offset = emu.call(lambda: tuple(emu.model.values["tcp_offset"]))
    finally:
        emu.stop()
    cart = PrimaryStreamDecoder().feed(b"".join(got))[2][1]["cartesian_info"]
    assert (cart.x, cart.y, cart.z, cart.rx, cart.ry, cart.rz) == pose
    offsets = (cart.tcp_offset_x, cart.tcp_offset_y, cart.tcp_offset_z)
    assert (*offsets, cart.tcp_offset_rx, cart.tcp_offset_ry, cart.tcp_offset_rz) == offset


def read_until(port: int, want: str, seconds: float = 5.0) -> list[object]:
    """Decoded messages of a port until the Robot State after one named `want` (or the time is up)."""
    decoder = PrimaryStreamDecoder()
    out: list[object] = []
    with socket.create_connection(("127.0.0.1", port), timeout=seconds) as sock:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            for _, message in decoder.feed(sock.recv(65536)):
                out.append(message)
                names = [getattr(m, "NAME", "") for m in out]
                if want in names and isinstance(message, RobotStateMessage) and names[-1] != want:
                    return out  # the Robot State after it too
    return out


def test_a_safety_mode_change_is_a_message_on_the_primary_port_not_the_secondary() -> None:
    emu = serve("5.15.0")
    try:
        import threading

        got: dict[str, list[object]] = {}
        readers = [
            threading.Thread(
                target=lambda n=n: got.__setitem__(n, read_until(emu.ports[n], "safety_mode_message", 2))
            )
            for n in ("primary", "secondary")
        ]
        for r in readers:
            r.start()
        time.sleep(0.5)
        emu.call(emu.model.values.__setitem__, "safety_mode", 3)  # PROTECTIVE_STOP
        for r in readers:
            r.join()
    finally:
        emu.stop()
    safety = [m for m in got["primary"] if getattr(m, "NAME", "") == "safety_mode_message"]
    assert len(safety) == 1 and safety[0].safety_mode_type == 3  # type: ignore[attr-defined]
    assert not any(getattr(m, "NAME", "") == "safety_mode_message" for m in got["secondary"])
    last = [m for m in got["primary"] if isinstance(m, RobotStateMessage)][-1]
    assert last["robot_mode_data"].is_protective_stopped and last["masterboard_data"].safety_mode == 3


def test_textmsg_and_a_script_that_cannot_run_become_robot_messages_on_the_primary_port() -> None:
    emu = serve("5.15.0")
    try:
        with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as sock:
            decoder = PrimaryStreamDecoder()
            sock.sendall(b'textmsg("hello")\n')
            time.sleep(0.5)
            sock.sendall(b"foo_bar_baz()\n")
            got: list[object] = []
            deadline = time.monotonic() + 5
            while time.monotonic() < deadline and "runtime_exception_message" not in [
                getattr(m, "NAME", "") for m in got
            ]:
                got += [m for _, m in decoder.feed(sock.recv(65536))]
    finally:
        emu.stop()
    by_name = {getattr(m, "NAME", ""): m for m in got}
    assert by_name["text_message"].text_message == "hello"  # type: ignore[attr-defined]
    assert by_name["key_message"].robot_message_title.startswith("PROGRAM_XXX_")  # type: ignore[attr-defined]
    failed = by_name["runtime_exception_message"]
    assert failed.script_line_number == 1 and "foo_bar_baz" in failed.runtime_exception_text_message  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("version", "arm", "expected", "kind", "box", "series"),
    [
        ("5.15.0", "UR10e", "UR10e", 2, 5, 3),
        ("3.15.8", None, "UR5", 1, 4, 2),
        ("5.15.0", "UR3e", "UR3e", 3, 6, 3),
    ],
)
def test_the_kinematics_sub_package_carries_the_chosen_arm(
    version: str, arm: str | None, expected: str, kind: int, box: int, series: int
) -> None:
    """Configuration Data also names the arm's controller box type and series as UnderAutomation's
    Universal Robots SDK 9.4 reads them (its ControllerBoxTypes and RobotSubTypes, which have no 0:
    with the 0s the emulator sent, its configuration_data raised '0 is not a valid ...')."""
    config = EmulatorConfig(
        rtde_port=None,
        primary_port=None,
        secondary_port=0,
        controller=version,
        arm=arm,
        realtime_port=None,
        dashboard_port=None,
    )
    with EmulatorThread(config) as emu:
        got = list(messages(emu.ports["secondary"], 2))
    state = PrimaryStreamDecoder().feed(b"".join(got))[1][1]
    assert tuple(state["kinematics_info"].dh_a) == arm_model(expected).dh.a
    conf = state["configuration_data"]
    assert (conf.robot_type, conf.reserved, conf.robot_sub_type) == (kind, box, series)


# in a fresh interpreter, as `rtde-spec serve` starts: once the emulator is made, the robot messages of
# a client connecting and of a program starting, in this thread's CPU seconds
FIRST_MESSAGES = """
import time
from rtde_spec.emulator.ports.robot_messages import event_messages, version_message
from rtde_spec.emulator.server import Emulator, EmulatorConfig
from rtde_spec.emulator.urscript.events import ScriptEvent
emu = Emulator(EmulatorConfig.free_ports(controller="5.15.0"))
start = time.thread_time()
version_message(emu.model.version, 0)
event_messages(ScriptEvent("program_started", "p", program="p"), 0)
event_messages(ScriptEvent("text", "hello"), 0)
print(time.thread_time() - start)
"""


def test_the_first_robot_messages_cost_the_control_loop_no_codec_build() -> None:
    """The primary codec costs some 40 ms of CPU to build. Built at the first robot message, the key
    message of a program's start (ur_rtde's control script) or a client's Version message, it held
    the control loop up for 5 to 30 e-Series steps, whose RTDE packages then left late in a burst;
    the emulator builds it when it is made (robot_messages.prepare), before it serves."""
    tree = str(Path(rtde_spec.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (tree, os.environ.get("PYTHONPATH")) if p)}
    out = subprocess.run(
        [sys.executable, "-c", FIRST_MESSAGES],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert float(out.stdout) < 0.005  # s of CPU: 0.2-0.3 ms; 38-40 ms when the codec was built here
