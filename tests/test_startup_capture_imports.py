"""What a one-package capture to Parquet does not import (issue 30.5, start-up): pyarrow's
filesystems (pyarrow.parquet loads S3, GCS, HDFS, Azure and `ssl`), OpenSSL through `hashlib`,
a thread pool for a single row group, or the writers of other formats."""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq
import pytest

from tests.capture_files import rtde_capture, rtde_packages
from tests.test_startup_imports import run_cli

NOT_NEEDED = {
    "pyarrow.parquet", "pyarrow.fs", "pyarrow._fs", "pyarrow._s3fs", "ssl", "_ssl", "_hashlib",
    "concurrent.futures.thread", "rtde_spec.output.mcap", "rtde_spec.output.jsonlines", "csv",
}  # fmt: skip


@pytest.fixture(scope="module")
def one_package(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return rtde_capture(tmp_path_factory.mktemp("pcap") / "one.pcap", rtde_packages(1))


def test_one_package_to_parquet_loads_only_what_it_writes_with(tmp_path: Path, one_package: Path) -> None:
    out = tmp_path / "out"
    code, modules, err = run_cli(tmp_path, "capture", str(one_package), "-o", str(out))
    assert code == 0, err
    assert not NOT_NEEDED & modules, sorted(NOT_NEEDED & modules)
    assert "pyarrow._parquet" in modules
    data = next(out.glob("rtde_outputs_1/*/*/*.parquet"))
    assert pq.read_table(data).column("robot_mode").to_pylist() == [0]


def test_the_other_formats_still_load_their_writers(tmp_path: Path, one_package: Path) -> None:
    for fmt, module in (("mcap", "rtde_spec.output.mcap"), ("jsonl", "rtde_spec.output.jsonlines")):
        out = tmp_path / fmt
        code, modules, err = run_cli(tmp_path, "capture", str(one_package), "-o", str(out), "--format", fmt)
        assert code == 0, err
        assert module in modules and list(out.rglob(f"*.{fmt}"))
