"""A failed recording never destroys an existing output (issue 18.1).

`record -o existing.csv` with a recipe the controller refuses, or a frequency it cannot
send, used to truncate the file to 0 bytes before the error. Now the output is written
beside its name and replaces the old file only once rows arrive: the old file stays
byte-identical and no temporary file is left.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec import EmulatorThread
from tests.faults.record_run import emulator, run, temp_files

OLD = {"csv": b"timestamp,actual_q_0\n1.0,2.0\n", "jsonl": b'{"timestamp":1.0}\n'}


@pytest.fixture(scope="module")
def emu() -> Iterator[EmulatorThread]:
    yield from emulator()


@pytest.mark.parametrize("fmt", ["csv", "jsonl"])  # Parquet opened its file at the first row already
@pytest.mark.parametrize(
    ("why", "extra", "fields"),
    [
        ("unknown field", [], "timestamp,no_such_output"),
        ("frequency the controller refuses", ["--frequency", "7000"], "timestamp"),
        ("frequency of zero", ["--frequency", "0"], "timestamp"),
    ],
)
def test_a_refused_recording_leaves_the_existing_file_byte_identical(
    emu: EmulatorThread, tmp_path: Path, fmt: str, why: str, extra: list[str], fields: str
) -> None:
    out = tmp_path / f"existing.{fmt}"
    out.write_bytes(OLD[fmt])
    result = run(emu, out, *extra, fields=fields)  # a later --frequency wins over the default one
    assert result.returncode != 0, result.stderr
    assert "error:" in result.stderr
    assert out.read_bytes() == OLD[fmt], f"{why}: the old file was changed"
    assert temp_files(tmp_path) == []


def test_a_refused_split_recording_leaves_earlier_parts_alone(emu: EmulatorThread, tmp_path: Path) -> None:
    old = {tmp_path / f"run_{i:04d}.csv": f"timestamp\n{i}.0\n".encode() for i in range(3)}
    for path, data in old.items():
        path.write_bytes(data)
    result = run(emu, tmp_path / "run.csv", "--split", "2s", fields="timestamp,no_such_output")
    assert result.returncode != 0 and "no_such_output" in result.stderr
    assert {p: p.read_bytes() for p in old} == old
    assert temp_files(tmp_path) == []


def test_a_recording_replaces_the_existing_file_once_rows_arrive(emu: EmulatorThread, tmp_path: Path) -> None:
    """The other half of the promise: a run that records does replace the file, whole."""
    out = tmp_path / "existing.csv"
    out.write_bytes(OLD["csv"])
    result = run(emu, out, "--samples", "300", fields="timestamp")
    assert result.returncode == 0, result.stderr
    # one line ending throughout: a header ending in CRLF above rows ending in LF was refused by DuckDB
    assert b"\r" not in out.read_bytes()
    lines = out.read_text().splitlines()
    assert lines[0] == "timestamp" and len(lines) == 301
    assert temp_files(tmp_path) == []
