"""A real third-party client against our emulator: ur_rtde from the package registry.

ur_rtde always connects to port 30004, and holds the GIL while it waits for a reply,
so the emulator runs as `rtde-spec serve` in its own process on 127.0.0.2.
"""

from __future__ import annotations

import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec import RtdeClient

rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")
import rtde_io  # noqa: E402

HOST = "127.0.0.2"
pytestmark = pytest.mark.fixed_ports(HOST)  # in turn with other runs (tests/fixed_ports.py)
SCENARIO = """
controller: 5.15.0
outputs:
  actual_q: [0.5, -1.0, 1.5, -0.5, 0.25, 2.0]
  actual_TCP_pose: [0.3, -0.2, 0.4, 3.1, 0.0, 0.1]
  robot_mode: 7
"""


def command() -> list[str]:
    exe = shutil.which("rtde-spec")
    return [exe] if exe else [sys.executable, "-m", "rtde_spec"]


# the dashboard and real-time ports left out: tests/test_docs.py holds 29999 in another process
NO_FIXED_PORTS = ("--dashboard-port", "-1", "--realtime-port", "-1")


def serve(args: list[str]) -> subprocess.Popen[str]:
    """`rtde-spec serve ARGS` in its own process; its RTDE port is in `.rtde_port`."""
    proc = subprocess.Popen(
        [*command(), "serve", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()  # "emulating controller 5.15.0 on HOST: rtde 30004, primary ..."
    assert "emulating controller" in line, proc.stderr.read() if proc.stderr else line
    proc.rtde_port = int(re.search(r"rtde (\d+)", line).group(1))  # type: ignore[attr-defined, union-attr]
    return proc


def wait_for_client(proc: subprocess.Popen[str], timeout: float = 30.0) -> None:
    """Until the emulator logs an RTDE client (a recorder's start-up takes long on a loaded machine)."""
    assert proc.stderr is not None
    seen = threading.Event()

    def read() -> None:
        for line in iter(proc.stderr.readline, ""):  # type: ignore[union-attr]
            if "RTDE client connected" in line:
                seen.set()

    threading.Thread(target=read, daemon=True).start()
    assert seen.wait(timeout), "the recorder never connected"


@pytest.fixture(scope="module")
def emulator(tmp_path_factory: pytest.TempPathFactory) -> Iterator[subprocess.Popen[str]]:
    scenario = tmp_path_factory.mktemp("scenario") / "s.yaml"
    scenario.write_text(SCENARIO)
    proc = serve(
        ["--host", HOST, "--primary-port", "0", "--secondary-port", "0", "--scenario", str(scenario)]
    )
    yield proc
    proc.terminate()
    proc.wait(10)


def test_ur_rtde_receive_reads_the_scenario_at_500_hz(emulator: subprocess.Popen[str]) -> None:
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0)
    try:
        time.sleep(0.3)
        assert receive.getActualQ() == pytest.approx([0.5, -1.0, 1.5, -0.5, 0.25, 2.0])
        assert receive.getActualTCPPose() == pytest.approx([0.3, -0.2, 0.4, 3.1, 0.0, 0.1])
        assert receive.getRobotMode() == 7
        start_ts, start = receive.getTimestamp(), time.monotonic()
        time.sleep(1.0)
        elapsed_controller = receive.getTimestamp() - start_ts
        assert elapsed_controller == pytest.approx(time.monotonic() - start, abs=0.1)  # real time
    finally:
        receive.disconnect()


def test_ur_rtde_io_writes_show_up_in_outputs_and_in_our_client(emulator: subprocess.Popen[str]) -> None:
    io = rtde_io.RTDEIOInterface(HOST)
    receive = rtde_receive.RTDEReceiveInterface(HOST, 500.0)
    try:
        assert io.setStandardDigitalOut(2, True)
        assert io.setToolDigitalOut(1, True)
        assert io.setSpeedSlider(0.3)
        assert io.setInputIntRegister(18, 1234)
        assert io.setInputDoubleRegister(18, 2.5)
        time.sleep(0.3)
        assert receive.getDigitalOutState(2)
        assert receive.getActualDigitalOutputBits() & (1 << 17)  # tool output 1
        assert receive.getTargetSpeedFraction() == pytest.approx(0.3)
        with RtdeClient(HOST) as ours:
            ours.setup_outputs(
                [
                    "actual_digital_output_bits",
                    "target_speed_fraction",
                    "input_int_register_18",
                    "input_double_register_18",
                ],
                125,
            )
            ours.start()
            record = ours.receive()
        assert record.actual_digital_output_bits & (1 << 2)
        assert record.target_speed_fraction == pytest.approx(0.3)
        assert (record.input_int_register_18, record.input_double_register_18) == (1234, 2.5)
    finally:
        io.disconnect()
        receive.disconnect()


@pytest.mark.slow  # a recording of seconds (test_record_signals covers signals in the plain run): CI runs it
def test_recorder_interrupted_keeps_its_rows(tmp_path: Path) -> None:
    proc = serve(["--rtde-port", "0", "--primary-port", "0", "--secondary-port", "0", *NO_FIXED_PORTS])
    out = tmp_path / "rec.csv"
    try:
        port = str(proc.rtde_port)  # type: ignore[attr-defined]
        rec = subprocess.Popen(
            [*command(), "record", "--host", "127.0.0.1", "--port", port, "--fields", "timestamp,actual_q",
             "--frequency", "500", "-o", str(out)],
            stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        wait_for_client(proc)
        time.sleep(1.5)
        rec.send_signal(signal.SIGINT)
        _, err = rec.communicate(timeout=10)
        assert rec.returncode == 0, err
        assert "stopped by interrupt" in err or "stopped by SIGINT" in err
        lines = out.read_text().splitlines()
        assert lines[0] == "timestamp,actual_q_0,actual_q_1,actual_q_2,actual_q_3,actual_q_4,actual_q_5"
        assert len(lines) > 300  # well over half a second at 500 Hz made it to the file
        assert all(len(line.split(",")) == 7 for line in lines)
    finally:
        proc.terminate()
        proc.wait(10)


@pytest.mark.slow  # a recording of seconds: CI runs it
def test_recorder_keeps_rows_when_the_controller_goes_away(tmp_path: Path) -> None:
    proc = serve(["--rtde-port", "0", "--primary-port", "0", "--secondary-port", "0", *NO_FIXED_PORTS])
    out = tmp_path / "rec.parquet"
    port = str(proc.rtde_port)  # type: ignore[attr-defined]
    rec = subprocess.Popen(
        [*command(), "record", "--host", "127.0.0.1", "--port", port, "--fields", "timestamp,robot_mode",
         "--frequency", "125", "-o", str(out)],
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    wait_for_client(proc)
    time.sleep(2.0)  # well past its setup, on a loaded machine
    proc.terminate()
    proc.wait(10)
    _, err = rec.communicate(timeout=10)
    assert rec.returncode == 1
    assert "stopped by connection" in err or "closed the connection" in err, err
    assert "error: the recording ended early: " in err, err  # and why
    import pyarrow.parquet as pq

    table = pq.read_table(out)
    assert table.num_rows > 50 and table.column_names == ["timestamp", "robot_mode"]
