"""Primary streams of controllers that send different fields (an older version leaves out the
last ones of a sub-package) in one output folder: a column a file holds only nulls in still has
the field's type, so pandas, pyarrow and DuckDB read the folder whichever file they take their
schema from. Before, such a column was of Arrow's null type and every reader refused the
folder when that file came first ("Unsupported cast from int64 to null").
"""

from __future__ import annotations

import struct
from pathlib import Path

import duckdb
import pyarrow.parquet as pq
import pytest
import yaml

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.cli.main import main

from .capture_files import Conversation, write

DATA = Path(__file__).parent / "data"
ROBOT_MODE = bytes.fromhex(yaml.safe_load((DATA / "primary_golden.yaml").read_text())[0]["hex"])


def without_last_byte(message: bytes) -> bytes:
    """The Robot State of a version without the Robot Mode Data's last field (`reserved`, 1 byte)."""
    sub = message[5:]
    cut = struct.pack(">I", len(sub) - 1) + sub[4:-1]
    return struct.pack(">I", 5 + len(cut)) + message[4:5] + cut


def primary(robot: str, message: bytes) -> Conversation:
    conv = Conversation(("192.168.56.1", 43001), (robot, 30001))
    conv.handshake()
    for _ in range(3):
        conv.send("server", message, dt=0.1)
    return conv


@pytest.mark.parametrize("older_first", [True, False])
def test_a_field_one_version_does_not_send_keeps_its_type(tmp_path: Path, older_first: bool) -> None:
    older = ("192.168.56.101" if older_first else "192.168.56.102", without_last_byte(ROBOT_MODE))
    newer = ("192.168.56.102" if older_first else "192.168.56.101", ROBOT_MODE)
    pcaps = [
        write(tmp_path / f"{n}.pcap", [primary(*robot)]) for n, robot in (("older", older), ("newer", newer))
    ]
    out = tmp_path / "tables"
    assert main(["capture", *map(str, pcaps), "-o", str(out)]) == 0
    folder = out / "primary_robot_mode_data"
    assert {str(pq.read_schema(f).field("reserved").type) for f in folder.rglob("*.parquet")} == {"int64"}
    table = pq.read_table(folder)  # the first file's schema (robot=...101 sorts first)
    reserved = dict(zip(table.column("robot").to_pylist(), table.column("reserved").to_pylist(), strict=True))
    assert reserved == {older[0]: None, newer[0]: 0}
    rows = duckdb.execute(
        f"SELECT count(*) FROM read_parquet('{folder}/**/*.parquet', hive_partitioning=1)"
    ).fetchall()
    assert rows == [(6,)]
    in_memory = capture_tables(pcaps[0])["primary_robot_mode_data"]
    assert str(in_memory.schema.field("reserved").type) == "int64"
