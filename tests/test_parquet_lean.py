"""Parquet files written without importing pyarrow.parquet (issue 30.5, start-up) are the files
pyarrow.parquet.ParquetWriter writes with the same settings, byte for byte."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from rtde_spec.output.parquet import LeanParquetWriter


def _table(start: int) -> pa.Table:
    n = 5000
    return pa.table(
        {
            "capture_time": np.arange(start, start + n, dtype=np.float64) * 0.002,
            "robot_mode": np.arange(n, dtype=np.int32) % 7,
            "bits": np.arange(n, dtype=np.uint64) << np.uint64(40),
            "connection": pa.array(["10.0.0.2:51000-10.0.0.10:30004"] * n),
        }
    )


SETTINGS = [
    {"use_dictionary": ["robot_mode", "bits"], "write_statistics": ["robot_mode"],
     "compression": {"capture_time": "none", "robot_mode": "snappy", "bits": "snappy", "connection": "none"}},
    {"use_dictionary": False, "write_statistics": False, "compression": "none"},
    {},
]  # fmt: skip


@pytest.mark.parametrize("settings", SETTINGS)
def test_lean_writer_writes_what_pyarrow_parquet_writes(tmp_path: Path, settings: dict[str, object]) -> None:
    tables = [_table(0), _table(5000)]
    ours, theirs = tmp_path / "ours.parquet", tmp_path / "theirs.parquet"
    lean = LeanParquetWriter(str(ours), tables[0].schema, **settings)
    full = pq.ParquetWriter(str(theirs), tables[0].schema, **settings)  # type: ignore[arg-type]
    for table in tables:
        lean.write_table(table, row_group_size=table.num_rows)
        full.write_table(table, row_group_size=table.num_rows)
    lean.close()
    full.close()
    assert ours.read_bytes() == theirs.read_bytes()
    assert pq.read_table(ours).equals(pa.concat_tables(tables))


def test_lean_writer_to_a_file_object_and_a_wrong_schema(tmp_path: Path) -> None:
    sink = io.BytesIO()
    lean = LeanParquetWriter(sink, _table(0).schema)
    lean.write_table(_table(0))
    with pytest.raises(ValueError, match="another schema"):
        lean.write_table(pa.table({"x": [1]}))
    lean.close()
    assert pq.read_table(io.BytesIO(sink.getvalue())).num_rows == 5000
    with pytest.raises(OSError):
        LeanParquetWriter(str(tmp_path / "no" / "such" / "folder.parquet"), _table(0).schema)
