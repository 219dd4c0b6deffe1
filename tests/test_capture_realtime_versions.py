"""Real-time streams of controllers of several versions in one output folder (a fleet of CB3 and
e-Series robots): every file of the `realtime` table has the same columns, so a reader that takes
the first file's schema (pandas, `pyarrow.dataset`, a CSV reader) loses no version's fields, and
`capture_tables` of one capture of both gives one table instead of an Arrow error.
"""

from __future__ import annotations

import csv
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.cli.main import main
from rtde_spec.realtime import encode
from rtde_spec.realtime.layout import all_columns, layout_for

from .capture_files import Conversation, write

OLD, NEW = ("192.168.56.101", "5.4.0"), ("192.168.56.102", "5.10.0")  # 1,116 and 1,220 bytes a message


def realtime(robot: str, version: str, count: int = 5) -> Conversation:
    conv = Conversation(("192.168.56.1", 43003), (robot, 30003))
    conv.handshake()
    for i in range(count):
        values = {"time": 10.0 + i * 0.008, "q_actual": [0.1 * i] * 6, "payload_mass": 1.5 + i}
        conv.send("server", encode(values, version), dt=0.008)
    return conv


def two_captures(tmp_path: Path) -> tuple[Path, Path]:
    return write(tmp_path / "old.pcap", [realtime(*OLD)]), write(tmp_path / "new.pcap", [realtime(*NEW)])


def test_every_layout_only_adds_columns_of_one_type() -> None:
    columns = all_columns()
    for version in ("3.0.0", "3.10.0", "5.4.0", "5.9.0", "5.10.0"):
        layout = layout_for(version)
        flat = [
            n if c == 1 else f"{n}_{i}"
            for n, c in zip(layout.names, layout.counts, strict=True)
            for i in range(c)
        ]
        assert flat == [n for n in columns if n in set(flat)], version  # same order
    assert columns["payload_mass"] == "f8?" and columns["robot_mode"] == "i8"  # since 5.10: nullable
    assert columns["q_actual_0"] == "f8"  # in every version: never null


def test_a_folder_of_two_versions_reads_every_column_from_the_first_file_on(tmp_path: Path) -> None:
    old, new = two_captures(tmp_path)
    out = tmp_path / "tables"
    assert main(["capture", str(old), str(new), "-o", str(out)]) == 0
    files = sorted((out / "realtime").rglob("*.parquet"))
    assert len(files) == 2
    schemas = [pq.read_schema(f) for f in files]
    assert schemas[0].names == schemas[1].names and schemas[0].types == schemas[1].types
    df = pq.read_table(out / "realtime").to_pandas()  # one dataset: the first file's schema
    assert len(df) == 10
    by_robot = {robot: rows for robot, rows in df.groupby("robot", observed=True)}
    assert by_robot[NEW[0]]["payload_mass"].tolist() == [1.5, 2.5, 3.5, 4.5, 5.5]
    assert by_robot[OLD[0]]["payload_mass"].isna().all()  # a 5.4 controller does not send it
    assert by_robot[OLD[0]]["q_actual_0"].round(6).tolist() == [0.0, 0.1, 0.2, 0.3, 0.4]


def test_csv_files_of_two_versions_share_one_header(tmp_path: Path) -> None:
    old, new = two_captures(tmp_path)
    out = tmp_path / "tables"
    assert main(["capture", str(old), str(new), "-o", str(out), "--format", "csv"]) == 0
    files = sorted((out / "realtime").rglob("*.csv"))
    tables = [list(csv.DictReader(f.open())) for f in files]
    headers = [f.open().readline() for f in files]
    assert headers[0] == headers[1] and "payload_mass" in headers[0]
    mass = {
        f.parent.parent.name: [row["payload_mass"] for row in rows]
        for f, rows in zip(files, tables, strict=True)
    }
    assert mass == {f"robot={OLD[0]}": [""] * 5, f"robot={NEW[0]}": ["1.5", "2.5", "3.5", "4.5", "5.5"]}


@pytest.mark.parametrize("order", [(OLD, NEW), (NEW, OLD)])
def test_one_capture_of_two_versions_is_one_arrow_table(
    tmp_path: Path, order: tuple[tuple[str, str], ...]
) -> None:
    pcap = write(tmp_path / "fleet.pcap", [realtime(*robot) for robot in order])
    table = capture_tables(pcap)["realtime"]  # an ArrowInvalid before: two schemas in one concat
    rows = table.to_pylist()
    assert len(rows) == 10
    mass = {r["robot"]: [] for r in rows}
    for r in rows:
        mass[r["robot"]].append(r["payload_mass"])
    assert mass == {OLD[0]: [None] * 5, NEW[0]: [1.5, 2.5, 3.5, 4.5, 5.5]}
