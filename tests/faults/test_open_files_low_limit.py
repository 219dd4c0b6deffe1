"""Descriptors stay bounded however many files a capture makes (issue 31.2).

480 files (80 robots x 3 days x 2 tables) under `ulimit -n 64`, a limit an eighth of the
file count: the real CLI in a child whose limit is set with `setrlimit`, every format,
every file complete, and the most descriptors the child held at once (sampled) well
under the limit. tests/faults/test_open_files.py holds 280 files under 256.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from tests.faults.many_files import fleet_capture, peak_descriptors, run_limited

ROBOTS, DAYS, PER_DAY = 80, 3, 4
LIMIT = 64


@pytest.fixture(scope="module")
def fleet(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fleet_capture(tmp_path_factory.mktemp("fleet") / "fleet.pcap", ROBOTS, DAYS, PER_DAY)


def rows_in(path: Path, fmt: str) -> int:
    if fmt == "parquet":
        return int(pq.read_metadata(path).num_rows)
    if fmt == "mcap":
        from mcap.reader import make_reader

        with open(path, "rb") as f:
            summary = make_reader(f).get_summary()
            assert summary is not None and summary.statistics is not None, path  # the footer is there
            return int(summary.statistics.message_count)
    lines = path.read_text().splitlines()
    if fmt == "jsonl":
        [json.loads(line) for line in lines]
    return len(lines) - (1 if fmt == "csv" else 0)


@pytest.mark.parametrize("fmt", ["parquet", "csv", "jsonl", "mcap"])
def test_480_files_under_64_descriptors(fleet: Path, tmp_path: Path, fmt: str) -> None:
    out = tmp_path / "tables"
    done = run_limited(LIMIT, "capture", str(fleet), "-o", str(out), "--format", fmt, cwd=tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    files = sorted(p for p in out.rglob(f"*.{fmt}"))
    assert len(files) == ROBOTS * DAYS * 2
    assert [p for p in out.rglob("*") if ".part-" in p.name] == []
    outputs = [p for p in files if "rtde_outputs_1" in p.parts]
    assert len(outputs) == ROBOTS * DAYS
    assert {rows_in(p, fmt) for p in outputs} == {PER_DAY}  # every table whole, none cut short
    peak = peak_descriptors(done.stderr)
    assert peak is not None and peak <= LIMIT // 2, (
        f"{peak} descriptors held at once under a limit of {LIMIT}"
    )


def _alive_with(marker: str) -> list[str]:
    """Processes whose command line holds `marker` (a test's own output folder)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            cmdline = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if proc.name.isdigit() and marker in cmdline:
            found.append(f"{proc.name}: {cmdline}")
    return found


def test_capture_jobs_short_of_descriptors_leaves_no_worker_behind(tmp_path: Path) -> None:
    """Under a limit just too low, the second worker failed to start after the first had: the
    command ended with its error, and the first (its death signal not set: it could not import
    ctypes) waited for work for ever, holding the caller's pipes open. Each limit in turn."""
    import os
    import resource
    import subprocess
    import sys
    import time

    from rtde_spec import build
    from tests.capture_files import Conversation, write

    captures = []
    for i in range(3):
        conv = Conversation(("10.0.0.2", 51000 + i), (f"10.0.0.{10 + i}", 30004))
        conv.handshake()
        conv.send("client", build("request_protocol_version", protocol_version=2))
        captures.append(str(write(tmp_path / f"c{i}.pcap", [conv])))
    for limit in range(10, 21):
        out = tmp_path / f"out-{limit}"

        def limited(limit: int = limit) -> None:
            resource.setrlimit(resource.RLIMIT_NOFILE, (limit, limit))

        argv = [sys.executable, "-m", "rtde_spec", "capture", *captures, "-o", str(out), "--jobs", "2"]
        argv.append("--lenient")
        with open(tmp_path / "err.txt", "wb") as err:
            done = subprocess.run(
                argv,
                stdout=subprocess.DEVNULL, stderr=err, preexec_fn=limited, timeout=120,
            )  # fmt: skip
        said = (tmp_path / "err.txt").read_text()
        assert done.returncode in (0, 1), said
        assert done.returncode == 0 or "out of file descriptors" in said, said
        deadline = time.monotonic() + 3.0
        while _alive_with(str(out)) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = _alive_with(str(out))
        for line in left:
            os.kill(int(line.split(":")[0]), 9)
        assert not left, f"ulimit -n {limit}: {left}"
