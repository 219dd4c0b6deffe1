"""Capture files with stretches of zeros, as real ones have them: a capture written to a
preallocated file (or stopped before it wrote its last blocks) ends in zeros, and a disk fault
can zero a region in the middle. Every frame around the zeros is decoded, the zeros are named
in the summary (exit 3), and they are passed in bulk: a pcap's zeros read as records holding
no frame, a pcapng's as no block type; before, every 16 bytes of them was a frame to decode.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.cli.main import main

from .capture_files import write
from .test_capture_driver import rtde_conversation


def session(tmp_path: Path, fmt: str) -> tuple[Path, bytes]:
    path = write(tmp_path / f"session.{fmt}", [rtde_conversation(count=25)], fmt=fmt)
    return path, path.read_bytes()


def rows(path: Path) -> list[dict[str, object]]:
    return capture_tables(path)["rtde_outputs_1"].to_pylist()  # type: ignore[no-any-return]


@pytest.mark.parametrize("fmt", ["pcap", "pcapng"])
def test_a_zero_filled_end_keeps_every_frame_and_is_named(
    tmp_path: Path, fmt: str, capsys: pytest.CaptureFixture[str]
) -> None:
    whole, data = session(tmp_path, fmt)
    padded = tmp_path / f"preallocated.{fmt}"
    padded.write_bytes(data + bytes(1 << 20))
    assert rows(padded) == rows(whole)
    assert len(rows(whole)) == 25
    assert main(["capture", str(padded), "-o", str(tmp_path / "out")]) == 3
    err = capsys.readouterr().err
    if fmt == "pcap":
        assert f"{(1 << 20) // 16} records that hold no frame (skipped)" in err
    else:
        assert "bytes skipped to the next whole record" in err


def test_zeros_in_the_middle_of_a_pcap_lose_no_frame_after_them(tmp_path: Path) -> None:
    whole, data = session(tmp_path, "pcap")
    # the 12th record starts where the first 11 records end: zero a hole in front of it
    at, k = 24, 0
    while k < 11:
        at += 16 + int.from_bytes(data[at + 8 : at + 12], "little")
        k += 1
    holed = tmp_path / "holed.pcap"
    holed.write_bytes(data[:at] + bytes(4096 + 8) + data[at:])  # not a whole number of headers
    assert rows(holed) == rows(whole)
    assert main(["capture", str(holed), "-o", str(tmp_path / "out")]) == 3
