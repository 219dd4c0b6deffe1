"""Both directions in capture order (issue 31.6): a capture that starts after the TCP handshake but
still holds the RTDE setup decodes as the same session with its handshake does.

Without a SYN each direction starts mid-stream; the client's few setup packages used to be
held for a 64 kB window they never fill, so they reached the decoder only at the end of
the file, after the controller's data, which was then "data packages without a recipe".
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables, decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from tests import capture_files


def session(path: Path, *, handshake: bool, text_first: bool = False) -> Path:
    conv = capture_files.Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    capture_files.rtde_setup(conv)
    if not handshake:
        conv.frames = conv.frames[2:]  # SYN and SYN-ACK are not in the capture
    for package in capture_files.rtde_packages(3000):
        conv.send("server", package)
    return capture_files.write(path, [conv])


@pytest.mark.parametrize("fmt", ["pcap", "pcapng"])
def test_the_same_session_with_and_without_its_handshake_gives_the_same_tables(
    tmp_path: Path, fmt: str
) -> None:
    full = capture_tables(session(tmp_path / f"full.{fmt}", handshake=True))
    late = capture_tables(session(tmp_path / f"late.{fmt}", handshake=False))
    assert sorted(full) == sorted(late) == ["rtde_outputs_1", "rtde_setup"]
    assert late["rtde_outputs_1"].num_rows == 3000
    assert late["rtde_outputs_1"].equals(full["rtde_outputs_1"])
    assert late["rtde_setup"].num_rows == full["rtde_setup"].num_rows


def test_no_recipe_problem_is_reported_for_a_late_capture_with_its_setup(tmp_path: Path) -> None:
    summary = decode_capture(session(tmp_path / "late.pcap", handshake=False), ArrowSink())
    assert summary.problems() == []
    assert summary.packages == 3006
