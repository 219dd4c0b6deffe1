"""A full disk never replaces a good output with a broken one (issue 31.1).

Two real faults: a small tmpfs that fills while `record` or `capture` writes (root can
mount one; CI runs as root), and ENOSPC injected under the writers in this process, so
the rules are held on any machine. Either way a failed write aborts the part file, an
existing file stays byte-identical, a text file in place keeps only whole lines, and
the error names the file, says the disk is full and what was kept.
"""

from __future__ import annotations

import errno
import hashlib
import io
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from rtde_spec import EmulatorThread
from rtde_spec.errors import OutputError
from rtde_spec.output.parquet import ParquetWriter
from rtde_spec.output.partfile import PartStream
from rtde_spec.output.writers import open_writer
from tests import capture_files
from tests.faults.record_run import emulator, run, temp_files
from tests.faults.tmpfs import fill, mounted_tmpfs

FORMATS = ["parquet", "csv", "jsonl", "mcap"]


@pytest.fixture(scope="module")
def emu() -> Iterator[EmulatorThread]:
    yield from emulator()


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 384 kB tmpfs of its own; skipped only where this process may not mount one."""
    where = tmp_path / "disk"
    where.mkdir()
    with mounted_tmpfs(where, "size=384k"):
        yield where


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def said_full(stderr: str, path: Path) -> None:
    assert "the disk is full" in stderr, stderr
    assert path.name in stderr, stderr
    assert "Errno" not in stderr, stderr


@pytest.mark.slow  # a recorder against the emulator until a tmpfs fills: 2-3 s CPU, 25-37 s loaded
@pytest.mark.parametrize("fmt", FORMATS)
def test_a_recording_on_a_filling_disk_keeps_the_existing_file(
    emu: EmulatorThread, small_disk: Path, fmt: str
) -> None:
    out = small_disk / f"run.{fmt}"
    first = run(emu, out, "--samples", "200")
    assert first.returncode == 0, first.stderr
    before = digest(out)
    fill(small_disk, 60_000)
    result = run(emu, out, "--samples", "20000")  # about 1 MB in any format: it cannot fit
    assert result.returncode != 0, result.stderr
    said_full(result.stderr, out)
    assert "the file that was there is as it was" in result.stderr
    assert digest(out) == before, "the good recording was replaced"
    assert temp_files(small_disk) == []


@pytest.mark.parametrize("fmt", ["csv", "jsonl"])
def test_a_new_text_recording_keeps_whole_lines_only(emu: EmulatorThread, small_disk: Path, fmt: str) -> None:
    out = small_disk / f"run.{fmt}"
    fill(small_disk, 60_000)
    result = run(emu, out, "--samples", "20000")
    assert result.returncode != 0
    said_full(result.stderr, out)
    assert "whole rows up to the last batch" in result.stderr
    data = out.read_bytes()
    assert data and data.endswith(b"\n"), data[-80:]
    lines = data.decode().splitlines()
    width = len(lines[0].split(",")) if fmt == "csv" else None
    for line in lines[1:]:  # every kept row is whole
        if width is not None:
            assert len(line.split(",")) == width, line
        else:
            assert line.startswith("{") and line.endswith("}"), line
    assert temp_files(small_disk) == []


def test_split_parts_closed_before_the_disk_filled_are_kept(emu: EmulatorThread, small_disk: Path) -> None:
    out = small_disk / "parts.parquet"
    fill(small_disk, 100_000)
    result = run(emu, out, "--samples", "20000", "--split", "20kB")
    assert result.returncode != 0
    assert "the disk is full" in result.stderr
    parts = sorted(small_disk.glob("parts_*.parquet"))
    assert parts, result.stderr
    assert f"{parts[0].name} .. {parts[-1].name} are complete" in result.stderr
    for part in parts:  # every kept part opens: it was closed before the disk filled
        assert pq.read_table(part).num_rows > 0
    assert temp_files(small_disk) == []


@pytest.mark.parametrize("fmt", ["parquet", "csv", "jsonl", "mcap"])
def test_a_capture_dataset_on_a_filling_disk_keeps_the_earlier_run(
    small_disk: Path, tmp_path: Path, fmt: str
) -> None:
    pcap = tmp_path / "robot.pcap"
    capture_files.rtde_capture(pcap, capture_files.rtde_packages(200))
    out = small_disk / "tables"
    first = capture_files.run_capture(str(pcap), "-o", str(out), "--format", fmt, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    before = {p: digest(p) for p in out.rglob("*") if p.is_file()}
    assert len(before) >= 2
    capture_files.rtde_capture(pcap, capture_files.rtde_packages(20_000))  # the same name, far bigger
    fill(small_disk, 40_000)
    result = capture_files.run_capture(str(pcap), "-o", str(out), "--format", fmt, cwd=tmp_path)
    assert result.returncode != 0
    assert "the disk is full" in result.stderr and "no table of" in result.stderr, result.stderr
    after = {p: digest(p) for p in out.rglob("*") if p.is_file()}
    assert after == before, "a table of the earlier run was replaced or a part file left"


class _FillsAfter(io.RawIOBase):
    """A file that takes `room` bytes, then fails with ENOSPC, as a full disk does (short write first)."""

    def __init__(self, real: io.RawIOBase, room: int) -> None:
        super().__init__()
        self.real, self.room = real, room

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self.real.fileno()

    def write(self, data: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        if self.room <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        taken = self.real.write(bytes(data[: self.room])) or 0
        self.room -= taken
        return taken

    def close(self) -> None:
        self.real.close()
        super().close()


def _inject(monkeypatch: pytest.MonkeyPatch, room: int) -> None:
    original = PartStream.__init__

    def init(self: PartStream, part: object, *, batched: bool = True) -> None:
        original(self, part, batched=batched)  # type: ignore[arg-type]
        self._file = _FillsAfter(self._file, room)  # type: ignore[assignment]

    monkeypatch.setattr(PartStream, "__init__", init)


def _batch(rows: int, start: float = 0.0) -> dict[str, np.ndarray]:
    return {
        "timestamp": np.arange(rows, dtype=float) + start,
        "actual_q": np.full((rows, 6), -1.5708),
    }


@pytest.mark.parametrize("fmt", ["csv", "jsonl", "mcap"])
@pytest.mark.parametrize("existing", [True, False])
def test_injected_enospc_never_commits_and_never_tears_a_line(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, fmt: str, existing: bool
) -> None:
    out = tmp_path / f"run.{fmt}"
    if existing:
        out.write_bytes(b"the old recording\n")
    _inject(monkeypatch, room=30_000)
    writer = open_writer(fmt, out, live=True)
    errors: list[OutputError] = []
    try:
        for i in range(50):
            writer.write_columns(_batch(100, start=i * 100))
            writer.flush()
    except OutputError as exc:  # where the format writes as it goes
        errors.append(exc)
    with pytest.raises(OutputError) as closing:  # closing after the error: still an error, never a commit
        writer.close()
    for error in [*errors, closing.value]:
        assert error.errno == errno.ENOSPC and str(out) in str(error) and "the disk is full" in str(error)
    assert temp_files(tmp_path) == []
    if existing:
        assert out.read_bytes() == b"the old recording\n"
    elif out.exists():  # a growing format in place: cut back to its last whole batch
        data = out.read_bytes()
        assert 0 < len(data) <= 30_000 and (data.endswith(b"\n") or fmt == "mcap")
        assert f"keeps the first {len(data)} bytes" in str(closing.value)
        if fmt == "mcap":  # whole chunks, read in order up to the end (no summary): none torn
            from mcap.exceptions import EndOfFile
            from mcap.stream_reader import StreamReader

            messages = 0
            with open(out, "rb") as f, pytest.raises(EndOfFile):
                for record in StreamReader(f, skip_magic=False).records:
                    messages += type(record).__name__ == "Message"
            assert messages > 0


def test_injected_enospc_in_parquet_discards_the_part(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    out = tmp_path / "run.parquet"
    out.write_bytes(b"PAR1 old")
    monkeypatch.setattr(ParquetWriter, "ROW_GROUP_ROWS", 100)
    writer = open_writer("parquet", out)
    writer.write_columns(_batch(100))  # one group written
    real = writer._writer.write_table  # type: ignore[attr-defined]

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "Error writing bytes to file. Detail: [errno 28] No space left on device")

    writer._writer.write_table = full  # type: ignore[attr-defined]
    with pytest.raises(OutputError):
        writer.write_columns(_batch(100, 100.0))
        writer.flush()
    assert real is not None
    with pytest.raises(OutputError, match="none of its rows were kept"):
        writer.close()
    assert out.read_bytes() == b"PAR1 old"
    assert temp_files(tmp_path) == []
