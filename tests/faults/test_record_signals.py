"""A recording survives the ways recordings end (issue 18.2).

SIGTERM (`timeout`, `kill`, systemd) and SIGHUP (a closed terminal) stop `record` as
cleanly as Ctrl-C: every row received before the signal is in a readable file, exit 0.
Against SIGKILL, `--split` closes finished parts, so only the open part is at risk, and
CSV is handed to the OS batch by batch, so a kill loses at most the last batch.
"""

from __future__ import annotations

import json
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec import EmulatorThread
from tests.faults.record_run import (
    HZ,
    SIGHUP,
    csv_rows,
    emulator,
    parts,
    record_then_signal,
    run,
    steps,
    temp_files,
)

pq = pytest.importorskip("pyarrow.parquet")

# a row the recorder received is written at most a batch (0.2 s) after it arrived; the
# margin is for a loaded machine (2 cores shared by many processes)
LATE = 1.5


@pytest.fixture(scope="module")
def emu() -> Iterator[EmulatorThread]:
    yield from emulator()


def stamps_of(path: Path) -> list[float]:
    if path.suffix == ".parquet":
        return [float(t) for t in pq.read_table(path).column("timestamp").to_pylist()]
    if path.suffix == ".jsonl":
        return [json.loads(line)["timestamp"] for line in path.read_text().splitlines()]
    return [float(row[0]) for row in csv_rows(path)]


@pytest.mark.parametrize(
    ("sig", "suffix"),
    [
        (signal.SIGTERM, ".parquet"),
        pytest.param(SIGHUP, ".parquet", marks=pytest.mark.slow),  # each signal and format once in
        pytest.param(signal.SIGTERM, ".jsonl", marks=pytest.mark.slow),  # the plain run; CI runs all
        (SIGHUP, ".csv"),
    ],
)
def test_a_signal_ends_the_recording_with_every_row_in_a_readable_file(
    emu: EmulatorThread, tmp_path: Path, sig: int, suffix: str
) -> None:
    out = tmp_path / f"run{suffix}"
    result, sent_until = record_then_signal(emu, out, sig, 2.5)
    assert result.returncode == 0, result.stderr
    assert f"stopped by {signal.Signals(sig).name}" in result.stderr
    stamps = stamps_of(out)
    assert len(stamps) > HZ, f"{len(stamps)} rows in 2.5 s at {HZ} Hz"
    assert steps(stamps) == {1}, "a row is missing"
    assert stamps[-1] >= sent_until - LATE, f"rows up to {stamps[-1]} of {sent_until} kept"
    assert temp_files(tmp_path) == []


@pytest.mark.slow  # seconds of real time (recording, a 5 s rule, a move): CI runs it
def test_sigkill_with_split_keeps_every_closed_parquet_part(emu: EmulatorThread, tmp_path: Path) -> None:
    out = tmp_path / "run.parquet"
    result, sent_until = record_then_signal(emu, out, signal.SIGKILL, 6.0, "--split", "2s")
    assert result.returncode == -signal.SIGKILL
    closed = parts(tmp_path, "run", ".parquet")
    assert len(closed) >= 2, f"parts {closed}, stderr {result.stderr}"
    assert [p.name for p in closed] == [f"run_{i:04d}.parquet" for i in range(len(closed))]
    stamps = [t for p in closed for t in stamps_of(p)]  # each part reads, in order, with no gap
    assert steps(stamps) == {1}
    assert stamps[-1] >= sent_until - 4.0 - LATE, "a part that was full is missing"
    left = temp_files(tmp_path)  # the open part, which a Parquet reader cannot open: no footer yet
    assert len(left) <= 1 and all(n.startswith(f".run_{len(closed):04d}.parquet.part-") for n in left)
    # the parts read as one dataset
    import pyarrow.dataset as ds

    assert ds.dataset([str(p) for p in closed], format="parquet").count_rows() == len(stamps)
    # the next run says what the killed one left, and replaces the parts as its own
    again = run(emu, out, "--split", "2s", "--samples", "100")
    assert again.returncode == 0, again.stderr
    if left:
        assert f"note: {tmp_path / left[0]} was left by a recording killed" in again.stderr
    assert [p.name for p in parts(tmp_path, "run", ".parquet")] == ["run_0000.parquet"]


@pytest.mark.slow  # seconds of real time (recording, a 5 s rule, a move): CI runs it
def test_sigkill_of_a_split_csv_loses_at_most_the_last_batch(emu: EmulatorThread, tmp_path: Path) -> None:
    result, sent_until = record_then_signal(emu, tmp_path / "run.csv", signal.SIGKILL, 5.0, "--split", "2s")
    assert result.returncode == -signal.SIGKILL
    found = parts(tmp_path, "run", ".csv")
    assert len(found) >= 2, f"parts {found}, stderr {result.stderr}"
    stamps = [float(row[0]) for p in found for row in csv_rows(p)]  # every line complete
    assert steps(stamps) == {1}, "a row is missing"
    # the open part is in place too, up to the last batch handed to the operating system
    assert stamps[-1] >= sent_until - LATE, f"rows up to {stamps[-1]} of {sent_until} kept"


def test_sigkill_of_an_mcap_recording_leaves_every_batch_but_the_last_in_place(
    emu: EmulatorThread, tmp_path: Path
) -> None:
    """MCAP waited for its summary at close in a hidden part file, its chunks (~1 MB) held
    first: a recorder killed after seconds left 40 bytes, every row lost. It is now in place
    from the first batch, each batch a whole chunk, which MCAP readers read in order without
    the summary (as `mcap recover` does)."""
    from mcap.exceptions import EndOfFile
    from mcap.stream_reader import StreamReader

    out = tmp_path / "run.mcap"
    result, sent_until = record_then_signal(emu, out, signal.SIGKILL, 2.5)
    assert result.returncode == -signal.SIGKILL
    assert temp_files(tmp_path) == [] and out.exists()
    stamps = []
    with open(out, "rb") as f:
        records = StreamReader(f, skip_magic=False).records
        with pytest.raises(EndOfFile):  # no summary, no footer: the reader meets the file's end
            for record in records:
                if type(record).__name__ == "Message":
                    stamps.append(json.loads(record.data)["timestamp"])
    assert len(stamps) > HZ, f"{len(stamps)} rows in 2.5 s at {HZ} Hz"
    assert steps(stamps) == {1}, "a row is missing"
    assert stamps[-1] >= sent_until - LATE, f"rows up to {stamps[-1]} of {sent_until} kept"
