"""Every frame twice: a capture on two interfaces (`dumpcap -i lo -i any`) or two capture points merged
(`mergecap`), the second copy of each frame a few milliseconds after the first.

Before: the second copy of the SYN, coming after the first copies of the first data segments,
restarted the stream, so every package of those first milliseconds was decoded twice: on a real
`dumpcap -i lo -i any` session the RTDE setup (8 packages) and 10 data packages, and 3 dashboard
replies, twice over, without a word. Now a SYN with the sequence number already seen is a copy,
not a new start. The second point's copy is a Linux cooked (SLL) frame, as `-i any` records it;
the two files are merged by mergecap (Debian's wireshark-common, which .ci/run installs with tshark).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from rtde_spec.capture.decoder import capture_tables
from tests.capture_files import Conversation, rtde_packages, rtde_setup, write
from tests.wireshark_tools import wireshark_tool

MERGECAP = wireshark_tool("mergecap")

LAG = 0.005  # the second copy of each frame: 5 ms later, the first copies of 2 data packages before it


def session(path: Path, link: str, start: float) -> Path:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004), link=link, time=start)
    rtde_setup(conv)
    for package in rtde_packages(50):
        conv.send("server", package)
    return write(path, [conv], "pcapng")


def columns(tables: dict[str, object], name: str, column: str) -> list[object]:
    return tables[name].column(column).to_pylist()  # type: ignore[attr-defined]


def test_frames_seen_twice_decode_once(tmp_path: Path) -> None:
    first = session(tmp_path / "lo.pcapng", "ethernet", 1_700_000_000.0)
    second = session(tmp_path / "any.pcapng", "sll", 1_700_000_000.0 + LAG)
    merged = tmp_path / "both.pcapng"
    subprocess.run([str(MERGECAP), "-w", str(merged), str(first), str(second)], check=True)
    once, twice = capture_tables(first), capture_tables(merged)
    assert columns(twice, "rtde_setup", "package") == columns(once, "rtde_setup", "package")
    stamps = columns(twice, "rtde_outputs_1", "timestamp")
    assert stamps == columns(once, "rtde_outputs_1", "timestamp") and len(stamps) == 50
