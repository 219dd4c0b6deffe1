"""A capture of any number of robots, tables and days works under a low descriptor limit (issue 31.2).

Every table × robot × day is a file; a fleet's capture has hundreds. The dataset keeps
a bounded number open (`DirectorySink.budget`) and the others give back their
descriptor until written again, in every format.
"""

from __future__ import annotations

import hashlib
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from rtde_spec.capture.tables.sink import DirectorySink
from tests import capture_files
from tests.helpers import ROOT

ROBOTS = 70  # x 2 days x 2 tables: 280 files, more than the 256 descriptors allowed


def fleet(path: Path, robots: int = ROBOTS) -> Path:
    packages = capture_files.rtde_packages(5)
    conversations = []
    for r in range(robots):
        for day in range(2):
            conv = capture_files.Conversation(
                (f"10.0.{r // 200 + 1}.{r % 200 + 1}", 51000 + day),
                (f"10.1.{r // 200}.{r % 200 + 1}", 30004),
                time=1_700_000_000.0 + day * 86_400 + r,
            )
            capture_files.rtde_setup(conv)
            for package in packages:
                conv.send("server", package)
            conversations.append(conv)
    return capture_files.write(path, conversations)


def capture_limited(pcap: Path, out: Path, fmt: str, limit: int | None) -> subprocess.CompletedProcess[str]:
    """The real CLI in a process whose descriptor limit is `limit` (None: as it is)."""

    def lower() -> None:
        if limit is not None:
            resource.setrlimit(resource.RLIMIT_NOFILE, (limit, limit))

    return subprocess.run(
        [sys.executable, "-m", "rtde_spec", "capture", str(pcap), "-o", str(out), "--format", fmt],
        capture_output=True,
        text=True,
        cwd=ROOT,
        preexec_fn=lower,
        timeout=300,
    )


def contents(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in folder.rglob("*")
        if p.is_file() and not p.name.startswith("recipes-")
    }


@pytest.fixture(scope="module")
def fleet_capture(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fleet(tmp_path_factory.mktemp("fleet") / "fleet.pcap")


@pytest.mark.parametrize("fmt", ["parquet", "csv", "jsonl", "mcap"])
def test_a_fleet_capture_under_256_descriptors_writes_every_table(
    fleet_capture: Path, tmp_path: Path, fmt: str
) -> None:
    limited = capture_limited(fleet_capture, tmp_path / "limited", fmt, 256)
    assert limited.returncode == 0, limited.stderr[-2000:]
    free = capture_limited(fleet_capture, tmp_path / "free", fmt, None)
    assert free.returncode == 0, free.stderr[-2000:]
    got, want = contents(tmp_path / "limited"), contents(tmp_path / "free")
    assert len(got) == ROBOTS * 2 * 2, sorted(got)[:5]
    if fmt in ("csv", "jsonl"):  # byte for byte the same files
        assert got == want
    else:
        assert sorted(got) == sorted(want)


def test_suspended_parquet_tables_reopen_where_they_stopped(tmp_path: Path) -> None:
    """Many Parquet tables written in turns through a budget of 4 open files: each reads back whole."""
    sink = DirectorySink(tmp_path, "parquet", "run", budget=4)
    from rtde_spec.output.parquet import ParquetWriter

    groups = ParquetWriter.ROW_GROUP_ROWS
    ParquetWriter.ROW_GROUP_ROWS = 50  # a row group per batch: every turn writes to the file
    try:
        for turn in range(6):
            for robot in range(12):
                column = np.arange(50, dtype=float) + turn * 50
                sink.columns("t", f"10.0.0.{robot}", "2024-01-01", {"timestamp": column})
        assert sum(1 for _ in tmp_path.rglob(".*part-*")) == 12
        sink.close()
    finally:
        ParquetWriter.ROW_GROUP_ROWS = groups
    files = sorted(tmp_path.rglob("*.parquet"))
    assert len(files) == 12
    for path in files:
        values = pq.read_table(path).column("timestamp").to_pylist()
        assert values == [float(v) for v in range(300)], path
