"""A real capture of a control session: dumpcap on loopback while ur_rtde's control and receive
interfaces (the pip package, unchanged) stream servoJ at 500 Hz against the emulator.

Real kernel ACKs and timing, real pcapng blocks, two RTDE connections side by side, input
packages between the outputs: the capture is read in runs (it was read frame by frame, 2x the
CPU), gives the frame-by-frame reading's tables, and holds one input package per servoJ call.
"""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.capture.protocols.rtde import RtdeConnection
from tests.capture_files import frame_by_frame, same_rows_per_connection
from tests.ur_rtde_robot import ur_rtde_robot
from tests.wireshark_tools import wireshark_tool

rtde_control = pytest.importorskip("rtde_control", reason="ur_rtde is installed by the test extra")
rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")

HOST = "127.0.0.63"
SECONDS = 2.0
pytestmark = [pytest.mark.slow, pytest.mark.fixed_ports(HOST)]


def _servo_session(path: Path) -> int:
    """dumpcap on loopback around a servoJ stream at 500 Hz; the number of servoJ calls."""
    dumpcap = wireshark_tool("dumpcap", ": a real capture of a control session")
    cap = subprocess.Popen(
        [dumpcap, "-i", "lo", "-f", f"host {HOST}", "-w", str(path)],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert cap.stderr is not None
        said = cap.stderr.readline() + cap.stderr.readline()  # "Capturing on 'Loopback: lo'"
        assert "Capturing on" in said, f"dumpcap did not start: {said}"
        calls = 0
        with ur_rtde_robot(HOST, rtde_control, rtde_receive) as robot:
            q = robot.receive.getActualQ()
            start = time.monotonic()
            while time.monotonic() - start < SECONDS:
                period = robot.control.initPeriod()
                target = [q[0] + 0.05 * (time.monotonic() - start), *q[1:]]
                assert robot.control.servoJ(target, 0.5, 0.5, 0.002, 0.1, 300)
                robot.receive.getActualQ()
                robot.control.waitPeriod(period)
                calls += 1
            robot.control.servoStop()
        time.sleep(0.3)  # the last frames written
    finally:
        cap.send_signal(signal.SIGINT)
        cap.wait(10)
    return calls


def test_a_real_control_session_capture_is_read_in_runs_with_every_servoj(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:

    path = tmp_path / "control.pcapng"
    calls = _servo_session(path)
    assert calls > 300
    carried: list[int] = []
    feed_run = RtdeConnection.feed_run

    def counted(self: RtdeConnection, sender: str, codec: object, rows: object, times: object) -> None:
        carried.append(len(times))  # type: ignore[arg-type]
        feed_run(self, sender, codec, rows, times)  # type: ignore[arg-type]

    with monkeypatch.context() as patch:
        patch.setattr(RtdeConnection, "feed_run", counted)
        tables = capture_tables(path)
    with monkeypatch.context() as patch:
        frame_by_frame(patch)
        one_by_one = capture_tables(path)
    same_rows_per_connection(tables, one_by_one)
    inputs = max(t.num_rows for name, t in tables.items() if name.startswith("rtde_inputs"))
    assert calls <= inputs <= calls + 10, (calls, inputs)  # one input package a servoJ, none lost
    data = sum(t.num_rows for name, t in tables.items() if name.startswith(("rtde_inputs", "rtde_outputs")))
    assert sum(carried) >= 0.8 * data, f"runs carried {sum(carried)} of {data} data packages"
