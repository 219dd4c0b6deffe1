"""A disk with no room for one more file is a full disk too (issue 31.1).

A file system runs out of inodes (or of blocks for a directory entry) before it runs out
of bytes: then making the next part file or partition folder fails with ENOSPC. That
used to escape as a bare `[Errno 28] ... '.x.csv.part-PID'`, and a capture committed
the tables it had made so far over the earlier run's. Now it is the same full disk as a
failed write: nothing of the run is put in place, the earlier files stay as they were,
and the error names the file and what was kept. Tried on a tmpfs with few inodes
(skipped only where this process may not mount one) and with ENOSPC injected when a part
file is made, so the rule is held on any machine.
"""

from __future__ import annotations

import errno
import hashlib
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from rtde_spec.capture.decoder import decode_to_directory
from rtde_spec.errors import OutputError
from rtde_spec.output import partfile, tempnames
from rtde_spec.output.writers import open_writer
from tests.capture_files import rtde_packages
from tests.faults.many_files import fleet_capture
from tests.faults.record_run import temp_files
from tests.faults.tmpfs import mounted_tmpfs


@pytest.fixture
def few_inodes(tmp_path: Path) -> Iterator[Path]:
    """A tmpfs of 4 MB but only 48 inodes; skipped only where this process may not mount one."""
    where = tmp_path / "disk"
    where.mkdir()
    with mounted_tmpfs(where, "size=4m,nr_inodes=48"):
        yield where


def use_up_inodes(disk: Path) -> int:
    """Make empty files until the file system has no inode left; how many it took."""
    spare = disk / "spare"
    spare.mkdir(exist_ok=True)
    made = 0
    while True:
        try:
            (spare / str(made)).touch()
        except OSError as exc:
            assert exc.errno == errno.ENOSPC, exc
            return made
        made += 1


def digests(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and "spare" not in p.parts
    }


def cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "rtde_spec", *args], capture_output=True, text=True, cwd=cwd, timeout=300
    )


def said_full(stderr: str, name: str) -> None:
    assert "the disk is full" in stderr, stderr
    assert name in stderr, stderr
    assert "Errno" not in stderr and ".part-" not in stderr, stderr  # the user's name, not a temporary one


@pytest.mark.parametrize("fmt", ["csv", "jsonl", "parquet", "mcap"])
def test_a_capture_with_no_room_for_its_next_file_keeps_the_earlier_run(
    few_inodes: Path, tmp_path: Path, fmt: str
) -> None:
    pcap = tmp_path / "fleet.pcap"
    fleet_capture(pcap, robots=2, days=1)
    out = few_inodes / "tables"
    first = cli("capture", str(pcap), "-o", str(out), "--format", fmt, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    before = digests(out)
    assert len(before) == 2 * 2 + 1  # setup and outputs per robot, and the recipe listing
    fleet_capture(pcap, robots=20, days=1)  # the same name: its tables replace the first run's
    use_up_inodes(few_inodes)
    result = cli("capture", str(pcap), "-o", str(out), "--format", fmt, cwd=tmp_path)
    assert result.returncode == 1, result.stderr
    said_full(result.stderr, "fleet-")
    assert "no table of" in result.stderr and "earlier runs are as they were" in result.stderr
    assert digests(out) == before, "a table of the failed run was put in place"
    assert [p for p in out.rglob("*") if ".part-" in p.name] == []


@pytest.mark.parametrize("fmt", ["csv", "jsonl", "parquet", "mcap"])
def test_decode_with_no_room_for_its_file_keeps_the_existing_one(
    few_inodes: Path, tmp_path: Path, fmt: str
) -> None:
    data = tmp_path / "packages.bin"
    data.write_bytes(b"".join(rtde_packages(500)))
    out = few_inodes / f"decoded.{fmt}"
    out.write_bytes(b"the earlier output\n")
    use_up_inodes(few_inodes)
    result = cli(
        "decode", str(data), "--recipe", "timestamp,actual_q,robot_mode", "-o", str(out), cwd=tmp_path
    )
    assert result.returncode == 1, result.stderr
    said_full(result.stderr, out.name)
    assert "the file that was there is as it was" in result.stderr
    assert out.read_bytes() == b"the earlier output\n"
    assert temp_files(few_inodes) == []


@pytest.fixture
def no_new_files(monkeypatch: pytest.MonkeyPatch) -> None:
    """ENOSPC whenever a part file is made, as a file system without a free inode answers."""
    real = open

    def refuse(path: object, mode: str = "r", *args: object, **kw: object) -> object:
        if tempnames.PART_MARK in str(path) and "w" in mode:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, mode, *args, **kw)  # type: ignore[call-overload]

    monkeypatch.setattr(partfile, "open", refuse, raising=False)


@pytest.mark.parametrize("fmt", ["csv", "jsonl", "mcap"])
def test_injected_no_room_for_a_file_keeps_the_existing_one(
    no_new_files: None, tmp_path: Path, fmt: str
) -> None:
    out = tmp_path / f"run.{fmt}"
    out.write_bytes(b"the old recording\n")
    with pytest.raises(OutputError) as failed:
        open_writer(fmt, out, live=True)
    error = failed.value
    assert error.errno == errno.ENOSPC
    assert str(out) in str(error) and "the disk is full" in str(error) and ".part-" not in str(error)
    assert "the file that was there is as it was" in str(error)
    assert out.read_bytes() == b"the old recording\n"
    assert temp_files(tmp_path) == []


@pytest.mark.parametrize("fmt", ["csv", "jsonl", "mcap"])  # Parquet's first files are pyarrow's: on the tmpfs
def test_injected_no_room_for_a_capture_table_keeps_the_earlier_run(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, fmt: str
) -> None:
    pcap = tmp_path / "fleet.pcap"
    fleet_capture(pcap, robots=3, days=1)
    out = tmp_path / "tables"
    decode_to_directory(pcap, out, fmt)
    before = digests(out)
    fleet_capture(pcap, robots=6, days=1)
    made: list[str] = []
    real = open

    def third_fails(path: object, mode: str = "r", *args: object, **kw: object) -> object:
        if tempnames.PART_MARK in str(path) and "w" in mode:
            made.append(str(path))
            if len(made) >= 3:  # two tables made, the third finds the disk full
                raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return real(path, mode, *args, **kw)  # type: ignore[call-overload]

    monkeypatch.setattr(partfile, "open", third_fails, raising=False)
    with pytest.raises(OutputError) as failed:
        decode_to_directory(pcap, out, fmt)
    assert "the disk is full" in str(failed.value) and "no table of" in str(failed.value)
    assert digests(out) == before, "a table of the failed run was put in place"
    assert [p for p in out.rglob("*") if ".part-" in p.name] == []


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_injected_no_room_for_the_name_keeps_the_existing_file(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, fmt: str
) -> None:
    """The rename into place can need a new directory block: ENOSPC there is the same full disk."""
    out = tmp_path / f"run.{fmt}"
    out.write_bytes(b"the old recording\n")
    writer = open_writer(fmt, out)
    writer.write_columns({"timestamp": np.arange(100, dtype=float)})
    real = partfile.os.replace

    def no_room(source: object, target: object) -> None:
        if Path(str(target)) == out:
            raise OSError(errno.ENOSPC, "No space left on device")
        real(source, target)  # type: ignore[arg-type]

    monkeypatch.setattr(partfile.os, "replace", no_room)
    with pytest.raises(OutputError) as failed:
        writer.close()
    assert failed.value.errno == errno.ENOSPC
    kept = "none of its rows were kept; the file that was there is as it was"
    assert str(failed.value) == f"file {out}: writing failed: the disk is full; {kept}"
    assert out.read_bytes() == b"the old recording\n"
    assert temp_files(tmp_path) == []
