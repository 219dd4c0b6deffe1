"""README's one-line queries of a capture dataset, run as written by DuckDB and Polars, on three robots.

The README promises that other engines read `rtde-spec capture` output directly; these
run its lines (the SQL of the DuckDB line, the Polars line as a command) on a dataset of
three robots and check the numbers, so a README line that stops working fails here.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

import pytest

from .capture_files import Conversation, write
from .test_capture import data, session
from .test_cli import cli

README = Path(__file__).resolve().parent.parent / "README.md"
ROBOTS = ("10.0.0.11", "10.0.0.12", "10.0.0.13")
PACKAGES = 20  # per robot; data(i) has actual_q_0 == i


def readme_line(prefix: str) -> str:
    lines = [line for line in README.read_text().splitlines() if line.startswith(prefix)]
    assert len(lines) == 1, f"README should have one line starting with {prefix!r}"
    return lines[0]


@pytest.fixture(scope="module")
def tables(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`rtde-spec capture` of three robots' captures into `<dir>/tables`; returns <dir>."""
    root = tmp_path_factory.mktemp("engines")
    for n, robot in enumerate(ROBOTS):
        conv = Conversation(("10.0.0.2", 51000 + n), (robot, 30004))
        session(conv)
        for i in range(PACKAGES):
            conv.send("server", data(i))
        write(root / f"robot{n}.pcap", [conv])
    result = cli("capture", *(str(root / f"robot{n}.pcap") for n in range(3)), "-o", str(root / "tables"))
    assert result.returncode == 0, result.stderr
    return root


def test_the_readme_duckdb_query_reads_the_dataset(tables: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import duckdb  # the test extra installs it

    line = readme_line('query = "SELECT')  # the README's Python block: query = "...", duckdb.sql(query)
    sql = ast.literal_eval(line.split("=", 1)[1].strip())
    monkeypatch.chdir(tables)
    rows = sorted(duckdb.sql(sql).fetchall())
    mean = sum(range(PACKAGES)) / PACKAGES
    assert rows == [(robot, PACKAGES, pytest.approx(mean)) for robot in ROBOTS]


def test_the_readme_polars_line_reads_the_dataset(tables: Path) -> None:
    line = readme_line("print(pl.scan_parquet(")
    code = f"import polars as pl; {line}"
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=tables, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    shape = re.search(r"shape: \((\d+), (\d+)\)", result.stdout)
    assert shape is not None, result.stdout
    # timestamp, actual_q_0..5, robot_mode, connection, capture_time, and the partitions robot, date
    assert (int(shape[1]), int(shape[2])) == (PACKAGES * len(ROBOTS), 12)
    assert ROBOTS[0] in result.stdout  # the robot partition is a column


def test_files_of_earlier_versions_with_nullable_columns_read_beside_new_ones(
    tables: Path, tmp_path: Path
) -> None:
    """Data columns became REQUIRED; a dataset that also holds files written before (OPTIONAL
    columns) still reads as one in DuckDB, Polars and Arrow."""
    import duckdb
    import polars as pl
    import pyarrow as pa
    import pyarrow.dataset as ds
    import pyarrow.parquet as pq

    new = next((tables / "tables" / "rtde_outputs_1").rglob("*.parquet"))
    old_style = pq.read_table(new)
    old_style = old_style.cast(pa.schema([f.with_nullable(True) for f in old_style.schema]))
    folder = tmp_path / "mixed" / "robot=old" / "date=2020-01-01"
    folder.mkdir(parents=True)
    pq.write_table(old_style, folder / "old.parquet")
    assert pq.ParquetFile(folder / "old.parquet").schema.column(0).max_definition_level == 1
    target = tmp_path / "mixed" / new.relative_to(tables / "tables" / "rtde_outputs_1")
    target.parent.mkdir(parents=True)
    target.write_bytes(new.read_bytes())
    rows = 2 * old_style.num_rows
    glob = str(tmp_path / "mixed" / "**" / "*.parquet")
    assert ds.dataset(tmp_path / "mixed", format="parquet", partitioning="hive").to_table().num_rows == rows
    assert duckdb.sql(f"SELECT count(*) FROM read_parquet('{glob}', hive_partitioning=1)").fetchall() == [
        (rows,)
    ]
    assert pl.scan_parquet(glob, hive_partitioning=True).collect().height == rows
