"""Real loopback traffic, captured by dumpcap while our client and ur_rtde talk to the emulator."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

import pytest

from rtde_spec import RtdeClient
from rtde_spec.capture.decoder import decode_to_directory
from tests.wireshark_tools import wireshark_tool

from .test_interop import serve

DUMPCAP = wireshark_tool("dumpcap", ": no live capture test")
HOST = "127.0.0.3"
pytestmark = pytest.mark.fixed_ports(HOST)  # in turn with other runs (tests/fixed_ports.py)


@pytest.mark.slow  # seconds of real time (recording, a 5 s rule, a move): CI runs it
def test_live_capture_of_our_client_and_ur_rtde(tmp_path: Path) -> None:
    rtde_receive = pytest.importorskip("rtde_receive", reason="ur_rtde is installed by the test extra")
    capture = tmp_path / "live.pcapng"
    proc = serve(["--host", HOST, "--primary-port", "0", "--secondary-port", "0"])
    dump = subprocess.Popen(
        [DUMPCAP, "-q", "-i", "lo", "-f", f"host {HOST} and tcp port 30004", "-w", str(capture)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        for _ in range(50):  # until dumpcap has opened its file
            if capture.exists() and capture.stat().st_size > 0:
                break
            time.sleep(0.1)
        time.sleep(0.5)
        with RtdeClient(HOST) as client:
            client.setup_outputs(["timestamp", "actual_q", "robot_mode"], 125)
            client.start()
            ours = [client.receive().timestamp for _ in range(100)]
            client.pause()
        theirs = rtde_receive.RTDEReceiveInterface(HOST, 500.0)
        time.sleep(0.5)
        theirs.disconnect()
        time.sleep(0.5)
    finally:
        dump.send_signal(signal.SIGTERM)
        dump.wait(10)
        proc.terminate()
        proc.wait(10)
    summary = decode_to_directory(capture, tmp_path / "out")
    assert [c.kind for c in summary.connections] == ["rtde", "rtde"]
    assert not summary.problems(), summary.problems()
    import pyarrow.dataset as ds

    ours_table = ds.dataset(
        tmp_path / "out" / "rtde_outputs_1", format="parquet", partitioning="hive"
    ).to_table()
    captured = set(ours_table.column("timestamp").to_pylist())
    assert set(ours) <= captured  # every package our client received is in the capture
    theirs_rows = summary.tables["rtde_outputs_2"]  # ur_rtde's 58-field recipe, at 500 Hz
    assert theirs_rows > 150
