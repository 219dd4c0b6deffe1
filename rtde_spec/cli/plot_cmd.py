"""rtde-spec plot TABLE FIELD... -o out.png: time on x, one line per vector component, units from the spec.

TABLE may be a file, one table's hive dataset (`OUT/rtde_outputs_1`), or the whole
folder `capture -o OUT` wrote: then the table holding the fields is picked (or named
with --table), and a dataset of several robots is plotted per robot (or one, --robot).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from rtde_spec.cli.conventions import describe, plural
from rtde_spec.errors import DecodeError, UsageError
from rtde_spec.printable import safe_text

EXIT_DAMAGED = 3  # the plot was written, but some of the table could not be read (said on stderr)
MAX_PROBLEMS = 20

TIME_COLUMNS = ("timestamp", "capture_time")
PARTITIONS = ("robot", "date")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plot",
        help="plot fields of a recorded or decoded table (CSV, Parquet, JSON Lines, or a dataset folder)",
        **describe(
            "Plots fields of a table against time, one line per vector component, units from the spec. "
            "TABLE: a .csv, .parquet or .jsonl file, a table folder of `capture -o OUT` "
            "(OUT/rtde_outputs_1), or OUT itself (the table with the fields is found); several robots "
            "are plotted one line each. UR's record.py recordings too (its CSV separated by spaces, "
            "its --binary form). Needs matplotlib (the plot extra).",
            "rtde-spec plot run.parquet actual_q -o run.png",
            "rtde-spec plot robot_data.csv actual_q -o q.png    # UR's record.py",
            "rtde-spec plot tables/ actual_q robot_mode -o q.png",
            "rtde-spec plot tables/rtde_outputs_1 actual_q --robot 10.0.0.10 -o q.png",
        ),
    )
    p.add_argument(
        "table",
        metavar="TABLE",
        help="a .csv, .parquet, .jsonl file, a hive dataset folder or a capture output folder (required)",
    )
    p.add_argument(
        "fields", nargs="+", metavar="FIELD", help="fields to plot; a vector plots all its components"
    )
    p.add_argument("-o", "--output", required=True, metavar="FILE.png", help="image to write (required)")
    p.add_argument("--time", metavar="COLUMN", help="time column (default: timestamp, else capture_time)")
    p.add_argument(
        "--table",
        dest="table_name",
        metavar="NAME",
        help="table of a capture output folder (default: the one holding the fields)",
    )
    p.add_argument(
        "--robot", metavar="ADDRESS", help="only this robot of a dataset of several (default: one line each)"
    )
    p.set_defaults(run=run)


def _has_parquet(folder: Path) -> bool:
    return any(folder.rglob("*.parquet"))


def tables_in(folder: Path) -> list[str]:
    """The tables of a capture output folder: sub-folders that are not hive partitions."""
    return sorted(p.name for p in folder.iterdir() if p.is_dir() and "=" not in p.name and _has_parquet(p))


def _schema_names(folder: Path) -> set[str]:
    from rtde_spec.output.hive import schema_names

    return schema_names(folder)


def pick_table(folder: Path, fields: list[str], name: str | None) -> Path:
    """The folder itself when it is one table; else the table that holds every field."""
    tables = tables_in(folder)
    if not tables:
        return folder
    if name is not None:
        if name not in tables:
            raise UsageError(f"no table {name!r}; the folder has: {', '.join(tables)}", subject=f"{folder}")
        return folder / name
    from rtde_spec.output.plots import components

    holding = [
        t for t in tables if all(components(dict.fromkeys(_schema_names(folder / t)), f) for f in fields)
    ]
    if len(holding) == 1:
        return folder / holding[0]
    if not holding:
        raise UsageError(
            f"no table has every field of {', '.join(fields)}; tables: {', '.join(tables)} "
            "(plot one with --table NAME)",
            subject=f"{folder}",
        )
    raise UsageError(
        f"several tables have {', '.join(fields)}: {', '.join(holding)}; name one with --table NAME",
        subject=f"{folder}",
    )


def load(path: Path, problems: list[str] | None = None) -> dict[str, list[Any]]:
    """The table's columns as lists (pyarrow reads Parquet; JSON Lines and CSV are read here).
    CSV cells that are not numbers are gaps in the plot; where a column holds numbers, each
    such cell, and each row cut short, is said in `problems` (a truncated file, a garbled cell)."""
    if path.is_dir() or path.suffix in (".parquet", ".pq"):
        from rtde_spec.output.hive import read_table

        table = read_table(path)
        return {name: table.column(name).to_pylist() for name in table.column_names}
    if path.suffix in (".jsonl", ".ndjson"):
        import json

        rows = []
        with open(path, encoding="utf-8", errors="replace") as f:
            for number, line in enumerate(f, 1):
                if line.strip():
                    try:
                        rows.append(json.loads(line))
                    except ValueError as exc:
                        raise DecodeError(f"line {number} is not JSON: {exc}", subject=f"{path}") from exc
        return {key: [row.get(key) for row in rows] for key in rows[0]} if rows else {}
    from rtde_spec.output.ur_recordings import binary_layout, read_binary

    if binary_layout(path) is not None:  # UR's record.py --binary
        return read_binary(path, problems if problems is not None else [])
    return _load_csv(path, problems if problems is not None else [])


def _load_csv(path: Path, problems: list[str]) -> dict[str, list[Any]]:
    import csv

    from rtde_spec.output.ur_recordings import separator

    nan = float("nan")
    texts: dict[str, list[tuple[int, str]]] = {}  # column -> (line, cell) of cells not numbers
    numbers: dict[str, int] = {}
    with open(path, newline="", encoding="utf-8", errors="replace") as f:
        between = separator(f.readline())  # UR's record.py separates by spaces
        f.seek(0)
        reader = csv.DictReader(f, delimiter=between)
        columns: dict[str, list[Any]] = {n: [] for n in reader.fieldnames or []}
        numbers = dict.fromkeys(columns, 0)
        for row in reader:
            line = reader.line_num
            if None in row:  # more cells than the header names
                problems.append(f"line {line}: {len(row[None])} cells more than the header's")  # type: ignore[index]
            short = [key for key, value in row.items() if key is not None and value is None]
            if short:
                kept = len(columns) - len(short)
                problems.append(f"line {line}: cut short ({kept} of {len(columns)} cells)")
            for key, value in row.items():
                if key is None or key not in columns:
                    continue
                try:
                    columns[key].append(float(value))  # type: ignore[arg-type]
                    numbers[key] += 1
                except (TypeError, ValueError):
                    columns[key].append(nan)
                    if value is not None and value.strip():
                        texts.setdefault(key, []).append((line, value))
    for key, cells in texts.items():
        if numbers[key]:  # a column of numbers with text in it; a column of text alone is no fault
            shown = ", ".join(f"line {line} {cell[:20]!r}" for line, cell in cells[:3])
            more = f" and {len(cells) - 3} more" if len(cells) > 3 else ""
            problems.append(f"column {key}: {plural(len(cells), 'cell')} not numbers ({shown}{more})")
    return columns


def split_robots(columns: dict[str, list[Any]], robot: str | None) -> dict[str, dict[str, list[Any]]]:
    """One set of columns per robot of a dataset (a single entry when there is no robot column)."""
    robots = columns.get("robot")
    if robots is None:
        if robot is not None:
            raise UsageError("--robot given, but the table has no robot column")
        return {"": columns}
    names = sorted({str(r) for r in robots})
    if robot is not None:
        if robot not in names:
            raise UsageError(f"no robot {robot!r} in the table; it has: {', '.join(names)}")
        names = [robot]
    out = {}
    for name in names:
        keep = [i for i, r in enumerate(robots) if str(r) == name]
        out[name] = {k: [v[i] for i in keep] for k, v in columns.items() if k not in PARTITIONS}
    return out


def _by_time(columns: dict[str, list[Any]], time_column: str) -> dict[str, list[Any]]:
    order = sorted(range(len(columns[time_column])), key=columns[time_column].__getitem__)
    return {k: [v[i] for i in order] for k, v in columns.items()}


def _check_output(output: Path) -> None:
    """-o names an image format matplotlib writes, in a folder that exists: before any reading."""
    from rtde_spec.errors import require

    bases = require("matplotlib.backend_bases", "plot", "plotting")
    kinds = bases.FigureCanvasBase.get_supported_filetypes()
    if output.suffix.lstrip(".").lower() not in kinds:
        raise UsageError(
            f"cannot tell the image format from the name; end it in .png, .svg or .pdf "
            f"(or any of {', '.join(sorted(kinds))})",
            subject=f"-o {output}",
        )
    if output.parent.exists() and not output.parent.is_dir():
        said = f"{output.parent} is a file, not a folder; give a path in a folder"
        raise UsageError(said, subject=f"-o {output}")
    if not output.parent.is_dir():
        raise UsageError(
            f"the folder {output.parent} does not exist; create it or write the image elsewhere",
            subject=f"-o {output}",
        )
    if output.is_dir():
        raise UsageError(
            f"is a directory; give the image's file name (e.g. {output / 'plot.png'})", subject=f"-o {output}"
        )


def run(args: argparse.Namespace) -> int:
    from rtde_spec.output.plots import components, plot_columns

    path = Path(args.table)
    if not path.exists():
        raise UsageError(
            "no such file or folder; give a .csv, .parquet or .jsonl file, a hive dataset folder or "
            "the folder of `rtde-spec capture -o OUT`",
            subject=f"file {path}",
        )
    _check_output(Path(args.output))
    if path.is_dir():
        path = pick_table(path, args.fields, args.table_name)
    problems: list[str] = []
    columns = load(path, problems)
    have = ", ".join(list(columns)[:12]) + (", ..." if len(columns) > 12 else "")
    time_column = args.time or next((c for c in TIME_COLUMNS if c in columns), None)
    if time_column is None or time_column not in columns:
        which = f"no column {time_column!r}" if time_column else f"no time column ({', '.join(TIME_COLUMNS)})"
        raise UsageError(
            f"{which}; the table has: {have}; name the time column with --time COLUMN",
            subject=f"file {path}",
        )
    missing = [f for f in args.fields if not components(columns, f)]
    if missing:
        raise UsageError(
            f"no column {', '.join(map(repr, missing))} (nor NAME_0, NAME_1, ... of a vector); "
            f"the table has: {have}",
            subject=f"file {path}",
        )
    per_robot = {
        robot: _by_time(cols, time_column) for robot, cols in split_robots(columns, args.robot).items()
    }
    plot_columns(per_robot, args.fields, time_column, args.output, title=str(path))
    print(f"wrote {args.output}")
    if problems:  # the plot holds what was read; what was not is said, and the exit code says so
        print(safe_text(f"{path}: cells that are not numbers are gaps in the plot"), file=sys.stderr)
        for problem in problems[:MAX_PROBLEMS]:
            print(safe_text(f"  problem: {problem}"), file=sys.stderr)
        if len(problems) > MAX_PROBLEMS:
            print(f"  ... and {len(problems) - MAX_PROBLEMS} more", file=sys.stderr)
        return EXIT_DAMAGED
    return 0
