"""A capture cut at a snap length by the real tool (`editcap -s 96`, as `dumpcap -s 96` keeps frames):
the cut frames are named with where they are in the capture, never decoded as if whole, and the
frames the snap length did not touch are all decoded.

Before: the summary said how many frames were cut and at how many bytes, not where: in a long
capture the user could not tell which part of it to take again. Now it gives the capture times
of the first and the last cut frame (UTC, as Wireshark's "UTC date and time" column).
editcap is Debian's wireshark-common, which .ci/run installs with tshark.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pyarrow.dataset as ds

from tests.capture_files import Conversation, rtde_packages, rtde_setup, run_capture, write
from tests.wireshark_tools import wireshark_tool

EDITCAP = wireshark_tool("editcap")

START = 1_700_000_000.0  # 2023-11-14 22:13:20 UTC


def session(tmp_path: Path) -> Path:
    """Dashboard requests and replies (short: never cut at 96 bytes) around RTDE data packages of
    64 bytes (cut: 42 bytes of payload fit in 96)."""
    rtde = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004), time=START)
    rtde_setup(rtde)
    dashboard = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 29999), time=START + 0.001)
    dashboard.handshake()
    for k, package in enumerate(rtde_packages(30)):
        rtde.send("server", package)
        if k % 3 == 0:
            dashboard.send("client", b"robotmode\n")
            dashboard.send("server", b"Robotmode: RUNNING\n")
    return write(tmp_path / "whole.pcapng", [rtde, dashboard], "pcapng")


def test_frames_cut_by_editcap_s_are_named_with_where_and_the_rest_decodes(tmp_path: Path) -> None:
    whole = session(tmp_path)
    cut = tmp_path / "cut96.pcapng"
    subprocess.run([str(EDITCAP), "-s", "96", str(whole), str(cut)], check=True)
    done = run_capture(str(cut), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 3, done.stderr
    first = next(line for line in done.stderr.splitlines() if "problem:" in line)
    assert "30 frames captured shorter than they were (96 bytes of each kept)" in first
    assert ", the first at 2023-11-14 22:13:20." in first and ", the last at 2023-11-14 22:13:20." in first
    assert "rtde_outputs" not in done.stdout  # never decoded as if whole
    replies = ds.dataset(tmp_path / "out" / "dashboard", format="parquet", partitioning="hive").to_table()
    assert replies.column("reply").to_pylist() == ["Robotmode: RUNNING"] * 10  # the rest: all of it
