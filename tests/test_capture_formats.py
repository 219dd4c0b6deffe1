"""What editcap makes of a capture: the same rows whatever the container, and a clear refusal of
the formats not read here.

The conversions (nanosecond pcap, pcapng with capture comments, a time shift, duplicates
removed) always gave the plain capture's rows; they are held to it here. Before: a file in a
format Wireshark reads but this reader does not (editcap -F modpcap, snoop, Network Monitor)
was refused as "not a pcap or pcapng file (magic 34cdb2a1)", naming no remedy; now the error
says what the file is and gives the editcap command that converts it. editcap is Debian's
wireshark-common, which .ci/run installs with tshark.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from tests.capture_files import Conversation, rtde_packages, rtde_setup, run_capture, write
from tests.wireshark_tools import wireshark_tool

EDITCAP = wireshark_tool("editcap")


def plain(tmp_path: Path) -> Path:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    for package in rtde_packages(100):
        conv.send("server", package)
    return write(tmp_path / "plain.pcap", [conv])


def editcap(*args: str) -> None:
    subprocess.run([str(EDITCAP), *args], check=True, capture_output=True)


def rows(path: Path, shift: float = 0.0) -> dict[str, list[dict[str, object]]]:
    out = {}
    for name, table in capture_tables(path).items():
        out[name] = [{**r, "capture_time": round(r["capture_time"] - shift, 6)} for r in table.to_pylist()]
    return out


@pytest.mark.parametrize(
    ("args", "shift"),
    [
        (["-F", "nsecpcap"], 0.0),
        (["-F", "pcapng", "--capture-comment", "robot 7, cell 3", "--capture-comment", "second"], 0.0),
        (["-F", "pcapng", "-t", "3600"], 3600.0),
        (["-d"], 0.0),
    ],
)
def test_editcap_conversions_give_the_same_rows(tmp_path: Path, args: list[str], shift: float) -> None:
    source = plain(tmp_path)
    converted = tmp_path / "converted"
    editcap(*args, str(source), str(converted))
    assert converted.read_bytes() != source.read_bytes()
    expected = rows(source)
    assert len(expected["rtde_outputs_1"]) == 100
    assert rows(converted, shift) == expected


def test_a_format_not_read_here_is_named_with_the_command_that_converts_it(tmp_path: Path) -> None:
    modified = tmp_path / "modified.pcap"
    editcap("-F", "modpcap", str(plain(tmp_path)), str(modified))
    done = run_capture(str(modified), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert "a modified pcap" in done.stderr
    assert f"editcap -F pcapng {modified} modified.pcapng" in done.stderr
    assert "Traceback" not in done.stderr
