"""Real clients watch the emulated arm move, held to what they do against URSim.

python-urx sends movej/movel on the secondary port (30002, fixed in urx) and waits by
watching the Robot State; ur_rtde's receive interface (RTDE on 30004, fixed) sees the
joints move while a movej sent to the primary port runs. Each test has a loopback
address of its own, so the fixed ports do not clash with other tests.
"""

from __future__ import annotations

import itertools
import re
import shutil
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.controller.model import HOME_Q
from rtde_spec.metamodel.arms import arm_model

urx_robot = pytest.importorskip("urx.urrobot", reason="python-urx is installed by the test extra")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")
pytestmark = pytest.mark.fixed_ports("127.0.0.23", "127.0.0.24")  # in turn with other runs


def test_urx_getters_and_waiting_moves_end_at_the_target() -> None:
    host = "127.0.0.23"
    # urx recognises the Robot State of CB3 controllers (3.x sizes); it is a CB3-era client
    config = EmulatorConfig(
        host=host,
        rtde_port=None,
        primary_port=None,
        secondary_port=30002,
        controller="3.15.0",
        arm="UR5",
        realtime_port=None,
        dashboard_port=None,
    )
    with EmulatorThread(config) as emu:
        robot = urx_robot.URRobot(host)
        try:
            assert robot.getj() == pytest.approx(HOME_Q, abs=1e-9)
            home_pose = kin.forward(arm_model("UR5"), HOME_Q)
            assert robot.getl() == pytest.approx(home_pose, abs=1e-9)
            target = [0.3, -1.4, 1.4, -1.6, -1.5, 0.2]
            started = time.monotonic()
            robot.movej(target, acc=1.4, vel=1.0, wait=True)
            assert time.monotonic() - started > 0.4  # it waited for the move
            assert robot.getj() == pytest.approx(target, abs=1e-6)
            pose = robot.getl()
            goal = [pose[0] + 0.05, pose[1] - 0.05, pose[2] + 0.03, *pose[3:]]
            robot.movel(goal, acc=0.5, vel=0.1, wait=True)
            assert robot.getl() == pytest.approx(goal, abs=1e-5)
            assert emu.model.values["runtime_state"] == 1  # STOPPED: the programs ended
        finally:
            robot.close()


def serve(host: str) -> tuple[subprocess.Popen[str], int]:
    """`rtde-spec serve` in its own process (ur_rtde holds the GIL while it waits for a reply,
    so an emulator thread in this process would starve); returns it and its primary port."""
    exe = shutil.which("rtde-spec")
    command = [exe] if exe else [sys.executable, "-m", "rtde_spec"]
    proc = subprocess.Popen(
        [*command, "serve", "--host", host, "--primary-port", "0", "--secondary-port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()  # "emulating controller 5.15.0 on HOST: rtde 30004, primary N, ..."
    found = re.search(r"primary (\d+)", line)
    assert found, proc.stderr.read() if proc.stderr else line
    return proc, int(found.group(1))


@pytest.mark.slow  # seconds of a move; test_interop runs ur_rtde in the plain run: CI runs it
def test_ur_rtde_receive_sees_the_joints_move_during_a_movej() -> None:
    host = "127.0.0.24"
    proc, primary_port = serve(host)
    try:
        receive = rtde_receive.RTDEReceiveInterface(host, 500.0)
        try:
            time.sleep(0.2)
            assert receive.getActualQ() == pytest.approx(HOME_Q)
            target = [0.8, -1.2, 1.2, -1.8, -1.3, 0.5]
            with socket.create_connection((host, primary_port)) as primary:
                primary.sendall(f"movej({target}, a=1.4, v=1.05)\n".encode())
                seen: list[list[float]] = []
                deadline = time.monotonic() + 10
                while time.monotonic() < deadline:
                    seen.append(receive.getActualQ())
                    if seen[-1] == pytest.approx(target, abs=1e-9) and not any(receive.getActualQd()):
                        break
                    time.sleep(0.02)
            moving = [q for q in seen if q != pytest.approx(HOME_Q) and q != pytest.approx(target)]
            assert len(moving) >= 10  # many samples on the way, not a jump
            first = np.array(seen[0])
            progress = [np.linalg.norm(np.array(q) - first) for q in seen]
            assert all(b >= a - 1e-9 for a, b in itertools.pairwise(progress))  # one way
            assert receive.getActualQ() == pytest.approx(target, abs=1e-9)
            pose = kin.forward(arm_model("UR5e"), target)
            assert receive.getActualTCPPose() == pytest.approx(pose, abs=1e-9)
        finally:
            receive.disconnect()
    finally:
        proc.terminate()
        proc.wait(10)
