"""rtde-spec plot TABLE FIELD... -o out.png: time on x, one line per vector component, units from the spec."""

from __future__ import annotations

import argparse
from pathlib import Path

from rtde_spec.errors import UsageError

TIME_COLUMNS = ("timestamp", "capture_time")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plot",
        help="plot fields of a recorded or decoded table (CSV, Parquet, JSON Lines, or a dataset folder)",
        description="Needs matplotlib: pip install 'rtde_spec[plot]'.",
    )
    p.add_argument(
        "table", metavar="TABLE", help="a .csv, .parquet, .jsonl file or a hive dataset folder (required)"
    )
    p.add_argument(
        "fields", nargs="+", metavar="FIELD", help="fields to plot; a vector plots all its components"
    )
    p.add_argument("-o", "--output", required=True, metavar="PNG", help="image to write (required)")
    p.add_argument("--time", help="time column (default: timestamp, else capture_time)")
    p.set_defaults(run=run)


def load(path: Path) -> dict[str, list[float]]:
    """The table's columns as lists (pyarrow reads every format; CSV falls back to the csv module)."""
    if path.is_dir() or path.suffix in (".parquet", ".pq"):
        from rtde_spec.errors import require

        dataset = require("pyarrow.dataset", "parquet", "plotting Parquet")
        table = dataset.dataset(path, format="parquet", partitioning="hive").to_table()
        return {name: table.column(name).to_pylist() for name in table.column_names}
    if path.suffix in (".jsonl", ".ndjson"):
        import json

        rows = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
        return {key: [row.get(key) for row in rows] for key in rows[0]} if rows else {}
    import csv

    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        columns: dict[str, list[float]] = {n: [] for n in reader.fieldnames or []}
        for row in reader:
            for key, value in row.items():
                try:
                    columns[key].append(float(value))
                except (TypeError, ValueError):
                    columns[key].append(float("nan"))
    return columns


def run(args: argparse.Namespace) -> int:
    from rtde_spec.output.plots import plot_columns

    path = Path(args.table)
    if not path.exists():
        raise UsageError("no such table", subject=f"file {path}")
    columns = load(path)
    time_column = args.time or next((c for c in TIME_COLUMNS if c in columns), None)
    if time_column is None or time_column not in columns:
        have = ", ".join(list(columns)[:12])
        raise UsageError(f"no time column; the table has: {have}", subject=f"file {path}")
    plot_columns(columns, args.fields, time_column, args.output)
    print(f"wrote {args.output}")
    return 0
