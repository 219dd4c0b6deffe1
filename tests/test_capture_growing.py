"""A capture still being written (dumpcap running, the newest file of a ring buffer) is decoded as it
was when it was opened, and the summary says the file grew meanwhile.

Before: the bytes written while it was read were passed over without a word: a file whose last
record happened to be whole then read as "ok", exit 0, though the file held more than the tables.
The writer here appends records while the reader is between blocks (its progress callback), as
dumpcap does while `capture` runs.
"""

from __future__ import annotations

from pathlib import Path

from rtde_spec.capture.decoder import decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import Conversation, rtde_packages, rtde_setup, write


def test_a_file_that_grows_while_it_is_read_is_said_to_have_grown(tmp_path: Path) -> None:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    packages = rtde_packages(200)
    for package in packages[:100]:
        conv.send("server", package)
    first = write(tmp_path / "first.pcap", [conv]).read_bytes()
    for package in packages[100:]:
        conv.send("server", package)
    later = write(tmp_path / "all.pcap", [conv]).read_bytes()[len(first) :]  # the records dumpcap adds
    growing = tmp_path / "growing.pcap"
    growing.write_bytes(first)

    def dumpcap_writes(_: int) -> None:
        with open(growing, "ab") as out:
            out.write(later)

    sink = ArrowSink()
    summary = decode_capture(growing, sink, progress=dumpcap_writes)
    assert sink.tables()["rtde_outputs_1"].num_rows == 100  # what the file held when opened
    (grew,) = [line for line in summary.damage() if "grew" in line]
    assert f"the file grew by {len(later)} bytes while it was read" in grew
