"""Captures split into parts, as `editcap -c`, `dumpcap -b` and `tcpdump -C` write them.

Before: each part was only ever a capture of its own, so every part after the first had its RTDE
data packages "without a recipe" and was told "the capture starts after the setup exchange: give
the recipe with --recipe FILE", though the recipe is in the first part beside it; a package cut
where one part ends was damage twice. Now the parts given as a list decode as one capture (the
rows of the whole file, `capture_tables` / `decode_capture`); `series.group` orders a folder's
files into their series; and a part decoded alone names its series and the command that joins
it (`mergecap -a`). The parts are written by editcap (Debian's wireshark-common, which .ci/run
installs with tshark).
"""

from __future__ import annotations

import random
import subprocess
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.capture.reading import series
from tests.capture_files import SMALL, Conversation, rtde_packages, rtde_setup, run_capture, write
from tests.wireshark_tools import wireshark_tool

EDITCAP, MERGECAP = wireshark_tool("editcap"), wireshark_tool("mergecap")


def whole(tmp_path: Path) -> Path:
    """An RTDE session whose stream is cut into 100-byte segments: packages straddle the parts."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    stream = b"".join(rtde_packages(300))
    for at in range(0, len(stream), 100):
        conv.send("server", stream[at : at + 100])
    return write(tmp_path / "whole.pcapng", [conv], "pcapng")


def split(source: Path, folder: Path, frames: int = 50) -> list[Path]:
    folder.mkdir()
    subprocess.run([str(EDITCAP), "-c", str(frames), str(source), str(folder / "part.pcapng")], check=True)
    parts = sorted(folder.iterdir())
    assert len(parts) > 3 and all(series.parts_of(p) is not None for p in parts)
    return parts


def rows(path: Path | list[Path]) -> dict[str, list[dict[str, object]]]:
    return {name: table.to_pylist() for name, table in capture_tables(path).items()}


def test_the_parts_decode_as_the_whole_capture(tmp_path: Path) -> None:
    source = whole(tmp_path)
    parts = split(source, tmp_path / "parts")
    shuffled = random.Random(1).sample(parts, len(parts))
    assert series.group([*shuffled, source]) == [parts, [source]]  # a series where its first part stood
    expected = rows(source)
    assert len(expected["rtde_outputs_1"]) == 300
    assert rows(series.group(shuffled)[0]) == expected


def test_a_part_decoded_alone_names_its_series_and_how_to_join_it(tmp_path: Path) -> None:
    parts = split(whole(tmp_path), tmp_path / "parts")
    done = run_capture(str(parts[2]), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 1, done.stderr  # data packages without their recipe
    assert "is a part of a split capture" in done.stderr and parts[0].name in done.stderr
    command = done.stderr.split("decode the parts as one capture: ")[1].split(" (the parts in order)")[0]
    assert command.startswith("mergecap -a -w whole.pcapng ")
    joined = subprocess.run(command, shell=True, cwd=tmp_path / "parts", capture_output=True, text=True)
    assert joined.returncode == 0, joined.stderr
    again = run_capture(str(tmp_path / "parts" / "whole.pcapng"), "-o", str(tmp_path / "out2"), cwd=tmp_path)
    assert again.returncode == 0 and "rtde_outputs_1 (300 rows)" in again.stdout, again.stderr


def test_tcpdump_parts_and_compressed_captures_are_found_and_ordered(tmp_path: Path) -> None:
    folder = tmp_path / "rotated"
    folder.mkdir()
    names = ["t.pcap", "t.pcap1", "t.pcap2", "t.pcap10", "other.pcap", "x.pcapng.gz", "notes.txt"]
    for name in names:
        (folder / name).write_bytes(b"")
    found = series.capture_files(folder)
    assert [p.name for p in found] == sorted(n for n in names if n != "notes.txt")
    grouped = [[p.name for p in g] for g in series.group(found)]
    assert grouped == [["other.pcap"], ["t.pcap", "t.pcap1", "t.pcap2", "t.pcap10"], ["x.pcapng.gz"]]
    assert [p.name for p in series.earlier(folder / "t.pcap10")] == ["t.pcap", "t.pcap1", "t.pcap2"]
    assert series.earlier(folder / "t.pcap") == [] and series.earlier(folder / "other.pcap") == []


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_the_command_decodes_a_folder_of_parts_as_one_capture(tmp_path: Path, jobs: str) -> None:
    """`rtde-spec capture FOLDER` of a ring buffer: one capture named after its first part, every
    row of the whole (before: 36 of 300 rows, every later part refused "without a recipe")."""
    source = whole(tmp_path)
    parts = split(source, tmp_path / "parts")
    gz = tmp_path / "parts" / "alone.pcapng.gz"  # a file compressed whole is found beside them
    subprocess.run(f"gzip -c {source} > {gz}", shell=True, check=True)
    done = run_capture(str(tmp_path / "parts"), "-o", str(tmp_path / "out"), "--jobs", jobs, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "rtde_outputs_1 (600 rows)" in done.stdout, done.stdout  # 300 of the series, 300 of the gz
    assert done.stdout.count(": 306 packages") == 2 and f"({len(parts)} parts)" in done.stdout
    written = sorted({p.name.split("-")[0] for p in (tmp_path / "out").rglob("*.parquet")})
    assert written == ["alone", "part"], written  # the series is named by its prefix, not a part


def test_a_ring_buffer_run_again_after_it_dropped_a_part_replaces_its_outputs(tmp_path: Path) -> None:
    """Named by the series, not its first part: the second run (oldest part gone, as a ring
    buffer drops it) replaces the first run's file instead of adding the rows both read again."""
    parts = split(whole(tmp_path), tmp_path / "parts")
    out = tmp_path / "out"
    assert run_capture(str(tmp_path / "parts"), "-o", str(out), cwd=tmp_path).returncode == 0
    first = sorted(out.rglob("rtde_outputs_1/**/*.parquet"))
    parts[0].unlink()  # its setup exchange goes with it: the rest needs the recipe now
    recipe = tmp_path / "recipe.txt"
    recipe.write_text("\n".join(SMALL) + "\n")
    again = run_capture(str(tmp_path / "parts"), "-o", str(out), "--recipe", str(recipe), cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    now = sorted(out.rglob("rtde_outputs_1/**/*.parquet"))
    assert [p.name for p in now] == [p.name for p in first], (first, now)
    assert 0 < sum(pq.read_metadata(p).num_rows for p in now) < 300
