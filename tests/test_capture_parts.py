"""A long capture in bounded memory (issue 30.6): a table's Parquet file whose footer (held by
pyarrow until the file closes) would grow past a bound is finished there, and the table goes
on in STEM_0001.parquet, ... beside it; every row is kept, in order, with or without workers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from rtde_spec.capture.tables.sink import DirectorySink
from rtde_spec.output.parquet import CHUNK_METADATA_BYTES, ParquetWriter

ROBOT, DAY = "10.0.0.10", "2023-11-14"
COLUMNS = 8  # capture_time, actual_q_0..5, robot_mode


def batch(start: int, rows: int) -> dict[str, object]:
    index = np.arange(start, start + rows)
    return {
        "capture_time": index * 0.002,
        "actual_q": np.repeat(index[:, None] * 0.5, 6, axis=1).astype(">f8"),  # as on the wire
        "robot_mode": (index % 7).astype(np.int32),
    }


def write(out: Path, batches: int, part_bytes: int, workers: int = 0, rows: int = 1000) -> DirectorySink:
    sink = DirectorySink(out, "parquet", "cap-0123abcd", workers=workers, part_bytes=part_bytes)
    for n in range(batches):
        sink.columns("rtde_outputs_1", ROBOT, DAY, batch(n * rows, rows))
        if n % 10 == 5:
            sink.row(
                "rtde_outputs_1",
                ROBOT,
                DAY,
                {"capture_time": -0.002, "actual_q": (-0.5,) * 6, "robot_mode": 6},
            )
    sink.close()
    return sink


@pytest.fixture(autouse=True)
def small_row_groups(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ParquetWriter, "ROW_GROUP_ROWS", 1000)  # a group per batch: parts come soon


def files(out: Path) -> list[Path]:
    return sorted(out.glob("rtde_outputs_1/*/*/*.parquet"))


@pytest.mark.parametrize("workers", [0, 2])
def test_a_table_goes_on_in_parts_past_the_bound_every_row_in_order(tmp_path: Path, workers: int) -> None:
    bound = 3 * COLUMNS * CHUNK_METADATA_BYTES  # a part holds 4 row groups
    sink = write(tmp_path / "out", 30, bound, workers)
    names = [p.name for p in files(tmp_path / "out")]
    assert names[0] == "cap-0123abcd.parquet" and names[1] == "cap-0123abcd_0001.parquet"
    assert len(names) >= 6, names
    tables = [pq.read_table(p) for p in files(tmp_path / "out")]
    assert all(t.num_rows <= 4 * 1001 for t in tables)
    times = [v for t in tables for v in t.column("capture_time").to_pylist()]
    expected = []
    for n in range(30):
        expected += (np.arange(n * 1000, n * 1000 + 1000) * 0.002).tolist()
        if n % 10 == 5:
            expected.append(-0.002)
    assert times == expected and sink.rows == {"rtde_outputs_1": len(expected)}
    assert sorted(str(p) for p in sink.paths) == [str(p) for p in files(tmp_path / "out")]
    assert len({t.schema for t in tables}) == 1, "every part has the columns of the first"


def test_parts_are_the_same_files_with_and_without_workers(tmp_path: Path) -> None:
    bound = 3 * COLUMNS * CHUNK_METADATA_BYTES
    write(tmp_path / "a", 25, bound)
    write(tmp_path / "b", 25, bound, workers=2)
    a, b = files(tmp_path / "a"), files(tmp_path / "b")
    assert [p.name for p in a] == [p.name for p in b]
    assert [p.read_bytes() for p in a] == [p.read_bytes() for p in b]


def test_a_shorter_rerun_removes_the_parts_it_did_not_write(tmp_path: Path) -> None:
    bound = 3 * COLUMNS * CHUNK_METADATA_BYTES
    write(tmp_path / "out", 30, bound)
    assert len(files(tmp_path / "out")) >= 6
    write(tmp_path / "out", 6, bound)
    kept = files(tmp_path / "out")
    assert [p.name for p in kept] == ["cap-0123abcd.parquet", "cap-0123abcd_0001.parquet"]
    assert sum(pq.read_table(p).num_rows for p in kept) == 6001


def test_a_failed_run_keeps_none_of_its_parts(tmp_path: Path) -> None:
    """Parts finished earlier are not put in place when the capture fails later (a full disk)."""
    bound = 3 * COLUMNS * CHUNK_METADATA_BYTES
    out = tmp_path / "out"
    sink = DirectorySink(out, "parquet", "cap-0123abcd", part_bytes=bound)
    for n in range(12):
        sink.columns("rtde_outputs_1", ROBOT, DAY, batch(n * 1000, 1000))
    assert len(sink.finished) == 3
    sink.abort()
    assert not [p for p in out.rglob("*") if p.is_file()]


def test_the_default_bound_leaves_a_million_packages_in_one_file() -> None:
    """58-field recipe: ~170 columns, 16,384-row groups; 1,000,000 packages are 62 groups."""
    held = 62 * 170 * CHUNK_METADATA_BYTES
    assert held < DirectorySink(Path("unused"), "parquet", "x").part_bytes < 3 * held
