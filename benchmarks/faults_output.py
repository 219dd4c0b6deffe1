"""Outputs under real faults, in figures (issue 31.1 and 31.2), for `faults.py`'s one run.

- a full disk: `decode -o` (the background writer thread) over an existing file on a
  filling tmpfs, and `capture` over an earlier run on a tmpfs that fills in bytes or has
  no inode left: was the earlier output kept, was it said, the exit code and the time;
- descriptors: a capture of 80 robots x 3 days (480 files) in every format, with no
  limit beside `ulimit -n 256` and `ulimit -n 64`: files written, seconds (and the ratio
  to the unlimited run in the same round), and the most descriptors held at once.

    python3 benchmarks/faults_output.py [--json]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

FORMATS = ("parquet", "csv", "jsonl", "mcap")
ROBOTS, DAYS = 80, 3  # x 2 tables: 480 files


@contextmanager
def tmpfs(where: Path, options: str) -> Iterator[bool]:
    """A tmpfs at `where` while the block runs; False where this process may not mount one."""
    where.mkdir(parents=True, exist_ok=True)
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", options, "bench", str(where)], capture_output=True
    )
    try:
        yield mounted.returncode == 0
    finally:
        if mounted.returncode == 0:
            subprocess.run(["umount", "-l", str(where)], check=False)


def _fill(disk: Path, leave: int) -> None:
    stat = os.statvfs(disk)
    (disk / "filler").write_bytes(b"\0" * max(0, stat.f_bavail * stat.f_frsize - leave))


def _no_inodes(disk: Path) -> None:
    spare = disk / "spare"
    spare.mkdir(exist_ok=True)
    n = 0
    while True:
        try:
            (spare / str(n)).touch()
        except OSError:
            return
        n += 1


def _digests(folder: Path) -> dict[str, str]:
    return {
        str(p): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in folder.rglob("*")
        if p.is_file() and "spare" not in p.parts and p.name != "filler"
    }


def _cli(*args: str, cwd: Path) -> tuple[subprocess.CompletedProcess[str], float]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "rtde_spec", *args], capture_output=True, text=True, cwd=cwd)
    return done, round(time.perf_counter() - start, 2)


def _said(stderr: str) -> str:
    lines = [line for line in stderr.strip().splitlines() if line.startswith("error:")]
    return lines[-1] if lines else ""


def full_disk_figures() -> list[dict[str, Any]]:
    """decode -o and capture on a disk that fills: what was kept, what was said, how long it took."""
    from tests.capture_files import rtde_packages
    from tests.faults.many_files import fleet_capture

    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        data = work / "packages.bin"
        data.write_bytes(b"".join(rtde_packages(20_000)))  # ~1 MB of text in any format
        with tmpfs(work / "disk", "size=384k") as mounted:
            if not mounted:
                return [{"case": "all", "outcome": "not measured: this process may not mount a tmpfs"}]
            disk = work / "disk"
            for fmt in FORMATS:
                for old in disk.iterdir():
                    old.unlink()
                out = disk / f"decoded.{fmt}"
                out.write_bytes(b"the earlier output\n")
                _fill(disk, 60_000)
                done, seconds = _cli(
                    "decode", str(data), "--recipe", "timestamp,actual_q,robot_mode", "-o", str(out), cwd=work
                )
                rows.append(
                    {"case": f"decode -o .{fmt}, disk fills", "exit": done.returncode, "seconds": seconds,
                     "earlier file kept": out.read_bytes() == b"the earlier output\n",
                     "part files left": sum(1 for p in disk.iterdir() if ".part-" in p.name),
                     "said": _said(done.stderr)}
                )  # fmt: skip
        pcap = work / "fleet.pcap"
        for fmt in ("parquet", "csv"):
            for how, options in (("disk fills", "size=384k"), ("no inode left", "size=4m,nr_inodes=48")):
                with tmpfs(work / f"disk-{fmt}-{how[:4]}", options) as mounted:
                    disk = work / f"disk-{fmt}-{how[:4]}"
                    fleet_capture(pcap, robots=2, days=1)
                    first, _ = _cli("capture", str(pcap), "-o", str(disk / "t"), "--format", fmt, cwd=work)
                    before = _digests(disk)
                    fleet_capture(pcap, robots=20, days=1, per_day=2000)  # ~1.3 MB of tables: cannot fit
                    _fill(disk, 40_000) if how == "disk fills" else _no_inodes(disk)
                    done, seconds = _cli(
                        "capture", str(pcap), "-o", str(disk / "t"), "--format", fmt, cwd=work
                    )
                    rows.append(
                        {"case": f"capture {fmt}, {how}", "exit": done.returncode, "seconds": seconds,
                         "earlier run kept": first.returncode == 0 and _digests(disk) == before,
                         "part files left": sum(1 for p in disk.rglob("*") if ".part-" in p.name),
                         "said": _said(done.stderr)}
                    )  # fmt: skip
    return rows


def open_file_figures() -> list[dict[str, Any]]:
    """A 480-file capture in every format: no limit, `ulimit -n 256`, `ulimit -n 64`."""
    from tests.faults.many_files import fleet_capture, peak_descriptors, run_limited

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        pcap = fleet_capture(work / "fleet.pcap", ROBOTS, DAYS)
        for fmt in FORMATS:
            free_seconds = None
            for limit in (0, 256, 64):
                out = work / f"{fmt}-{limit}"
                start = time.perf_counter()
                done = run_limited(limit, "capture", str(pcap), "-o", str(out), "--format", fmt, cwd=work)
                seconds = time.perf_counter() - start
                free_seconds = free_seconds or seconds
                files = sum(1 for p in out.rglob("*") if p.is_file() and not p.name.startswith("recipes-"))
                rows.append(
                    {"format": fmt, "ulimit -n": limit or "none", "exit": done.returncode,
                     "files": f"{files} of {ROBOTS * DAYS * 2}", "seconds": round(seconds, 2),
                     "x unlimited": round(seconds / free_seconds, 2),
                     "peak descriptors": peak_descriptors(done.stderr)}
                )  # fmt: skip
    return rows


def print_figures(figures: dict[str, Any]) -> None:
    print("full disk: decode -o and capture over earlier outputs on a filling tmpfs")
    for row in figures["full disk outputs"]:
        print("  " + ", ".join(f"{k} {v}" for k, v in row.items()))
    print(f"open files: a {ROBOTS}-robot, {DAYS}-day capture ({ROBOTS * DAYS * 2} files) under limits")
    for row in figures["open files, 480"]:
        print("  " + ", ".join(f"{k} {v}" for k, v in row.items()))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print JSON")
    args = parser.parse_args()
    figures = {"full disk outputs": full_disk_figures(), "open files, 480": open_file_figures()}
    if args.json:
        print(json.dumps(figures, indent=2, default=str))
    else:
        print_figures(figures)
    return 0


if __name__ == "__main__":
    sys.exit(main())
