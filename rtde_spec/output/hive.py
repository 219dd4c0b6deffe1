"""Read a Parquet file, or a hive-partitioned folder of them (what `capture` writes), into one table.

Not through `pyarrow.dataset`: importing it imports pandas (pyarrow's pandas
compatibility layer), a third of a second before a plot can start. The folders here
are ours and simple: `key=value` folder names (robot, date) become text columns, the
files' schemas are unified, and files still being written (`.NAME.part-PID`) are skipped.

Partition values are percent-escaped in folder names as pyarrow writes them (and Hive and Spark
escape): every byte but letters, digits and `-._~`, so an IPv6 robot `fd00::d3` is the folder
`robot=fd00%3A%3Ad3`, which pyarrow, DuckDB, Polars and Spark read back as `fd00::d3`
(docs/decisions.md).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from urllib.parse import quote, unquote

from rtde_spec.errors import DecodeError, require


def parquet_files(path: Path) -> list[Path]:
    """The Parquet files of a file or folder, in path order; temporary part files left out."""
    if path.is_file():
        return [path]
    return sorted(p for p in path.rglob("*.parquet") if not p.name.startswith("."))


def partition_folder(key: str, value: str) -> str:
    """The folder name `key=value` of a partition, its value percent-escaped as pyarrow writes it."""
    return f"{key}={quote(value, safe='')}"


def partitions(file: Path, root: Path) -> dict[str, str]:
    """The `key=value` folders between `root` and `file`, as {key: value} (values unescaped)."""
    if file == root:
        return {}
    keys: dict[str, str] = {}
    for part in file.relative_to(root).parts[:-1]:
        key, sep, value = part.partition("=")
        if sep and key:
            keys[key] = unquote(value)
    return keys


def schema_names(path: Path) -> set[str]:
    """Every column name of a file or folder: the files' own columns and the partition keys."""
    pq = require("pyarrow.parquet", "parquet", "plotting Parquet")
    names: set[str] = set()
    for file in parquet_files(path):
        names |= set(_read(pq, file, "schema").names) | set(partitions(file, path))
    return names


def read_table(path: Path) -> Any:
    """One Arrow table of a Parquet file or hive folder; a file that is not Parquet is a DecodeError."""
    import numpy as np

    from rtde_spec.output.tables import arrow_array

    pa = require("pyarrow", "parquet", "plotting Parquet")
    pq = require("pyarrow.parquet", "parquet", "plotting Parquet")
    files = parquet_files(path)
    if not files:
        raise DecodeError("no Parquet files", subject=f"{path}")
    tables = []
    for file in files:
        table = _read(pq, file, "table")
        for key, value in partitions(file, path).items():
            if key not in table.column_names:  # built from numpy: pa.array of texts imports pandas
                table = table.append_column(key, arrow_array(np.full(len(table), value)))
        tables.append(table)
    try:
        return pa.concat_tables(tables, promote_options="permissive")
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:
        raise DecodeError(f"the files' columns do not combine: {exc}", subject=f"{path}") from exc


def _read(pq: Any, file: Path, what: str) -> Any:
    import pyarrow as pa

    try:
        parquet = pq.ParquetFile(file)
        return parquet.schema_arrow if what == "schema" else parquet.read()
    except (pa.ArrowInvalid, pa.ArrowTypeError, OSError) as exc:
        raise DecodeError(f"not a readable Parquet table or dataset: {exc}", subject=f"{file}") from exc
