"""The robot partition of an IPv6 controller reads back as its address in every engine.

Before: the folder was `robot=fd00__10` (':' made '_'), so pyarrow, DuckDB and Polars gave the
robot as `fd00__10`, which is no address and could be another one's (`fd00::10` and a
`fd00__10` alike). Now the value is percent-escaped as pyarrow writes hive partitions
(`robot=fd00%3A%3A10`), which each engine unescapes (docs/decisions.md). A re-run over an
output folder an earlier version wrote removes that input's files from the old-named folder.
"""

from __future__ import annotations

from pathlib import Path

import duckdb
import polars as pl
import pyarrow.dataset as ds

from rtde_spec.capture.decoder import decode_to_directory
from rtde_spec.output import hive
from tests.capture_files import Conversation, rtde_packages, rtde_setup, write

ROBOT = "fd00::10"


def ipv6_capture(path: Path, robot: str = ROBOT) -> Path:
    conv = Conversation(("fd00::2", 51000), (robot, 30004))
    rtde_setup(conv)
    for package in rtde_packages(20):
        conv.send("server", package)
    return write(path, [conv], "pcapng")


def test_an_ipv6_robot_reads_back_as_its_address_in_every_engine(tmp_path: Path) -> None:
    decode_to_directory(ipv6_capture(tmp_path / "v6.pcapng"), tmp_path / "out")
    table = tmp_path / "out" / "rtde_outputs_1"
    assert [p.name for p in table.iterdir()] == ["robot=fd00%3A%3A10"]
    by_pyarrow = ds.dataset(table, format="parquet", partitioning="hive").to_table()
    assert set(by_pyarrow.column("robot").to_pylist()) == {ROBOT}
    query = f"SELECT DISTINCT robot FROM read_parquet('{table}/**/*.parquet', hive_partitioning=1)"
    assert duckdb.sql(query).fetchall() == [(ROBOT,)]
    by_polars = pl.scan_parquet(f"{table}/**/*.parquet", hive_partitioning=True).collect()
    assert set(by_polars["robot"].to_list()) == {ROBOT}
    assert set(hive.read_table(table).column("robot").to_pylist()) == {ROBOT}  # `rtde-spec plot`'s reader


def test_partition_folder_names_round_trip() -> None:
    for value in ("10.0.0.10", "fd00::10", "fe80::1%lo", "2001:db8::1", "unknown", "2026-11-26"):
        folder = hive.partition_folder("robot", value)
        assert "/" not in folder and ":" not in folder and folder.count("=") == 1
        assert hive.partitions(Path("t") / folder / "f.parquet", Path("t")) == {"robot": value}
    assert hive.partition_folder("robot", "10.0.0.10") == "robot=10.0.0.10"  # IPv4 folders as before


def test_a_rerun_removes_the_files_an_earlier_version_wrote_under_the_old_name(tmp_path: Path) -> None:
    capture, out = ipv6_capture(tmp_path / "v6.pcapng"), tmp_path / "out"
    summary = decode_to_directory(capture, out)
    (written,) = [Path(p) for p in summary.paths if "rtde_outputs_1" in p]
    old = out / "rtde_outputs_1" / "robot=fd00__10" / written.parent.name / written.name
    if written != old:  # as the earlier version left it
        old.parent.mkdir(parents=True)
        written.rename(old)
        written.parent.rmdir()
    decode_to_directory(capture, out)
    assert not (out / "rtde_outputs_1" / "robot=fd00__10").exists()
    rows = ds.dataset(out / "rtde_outputs_1", format="parquet", partitioning="hive").to_table()
    assert rows.num_rows == 20 and set(rows.column("robot").to_pylist()) == {ROBOT}


def test_a_rerun_of_a_changed_capture_leaves_none_of_the_earlier_runs_tables(tmp_path: Path) -> None:
    """The same file, without its data the second time: the tables its first run wrote and the
    second did not stayed beside the second's (15 primary tables of a capture that no longer
    had the primary connection), read as rows of this capture. Another input's stay."""
    import yaml

    from rtde_spec import build
    from tests.helpers import DATA

    capture, out = tmp_path / "robot.pcapng", tmp_path / "out"
    cases = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
    golden = {c["message"]: bytes.fromhex(c["hex"]) for c in cases}
    primary = Conversation(("fd00::2", 52000), (ROBOT, 30001))
    primary.handshake()
    primary.send("server", golden["robot_mode_data"])
    data = Conversation(("fd00::2", 51000), (ROBOT, 30004))
    rtde_setup(data)
    for package in rtde_packages(20):
        data.send("server", package)
    write(capture, [data, primary], "pcapng")
    other = Conversation(("fd00::3", 51000), (ROBOT, 30004))
    rtde_setup(other)
    for package in rtde_packages(3):
        other.send("server", package)
    write(tmp_path / "other.pcapng", [other], "pcapng")
    decode_to_directory(tmp_path / "other.pcapng", out)  # another input's tables stay
    first = decode_to_directory(capture, out)
    assert any("primary_robot_mode_data" in p for p in first.paths)
    shorter = Conversation(("fd00::2", 51000), (ROBOT, 30004))  # the same robot, no data now
    shorter.handshake()
    shorter.send("client", build("request_protocol_version", protocol_version=2))
    write(capture, [shorter], "pcapng")
    second = decode_to_directory(capture, out)
    files = {str(p) for p in out.rglob("*.parquet") if p.name.startswith("robot-")}
    assert files == set(second.paths), files
    assert not any("rtde_outputs_1" in p or "primary_" in p for p in files)
    assert not (out / "primary_robot_mode_data").exists()  # a table of this capture alone
    assert [p.name.split("-")[0] for p in (out / "rtde_outputs_1").rglob("*.parquet")] == ["other"]
