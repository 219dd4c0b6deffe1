"""`decode -o` on a full disk: its background writer thread hands the error over (issue 31.1).

decode writes through a second thread (output/background.py); a write error there must
reach the caller, end the part file and exit 1 with the file's name, never be swallowed
into an exit 0 or a file without its end. Tried on a tmpfs that fills (skipped only where
this process may not mount one) and on /dev/full, the device every write to which fails
with ENOSPC (written directly, as a device is: it used to say only "[Errno 28]").
"""

from __future__ import annotations

import os
import subprocess
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.capture_files import rtde_packages
from tests.faults.record_run import temp_files

FORMATS = ["parquet", "csv", "jsonl", "json", "mcap", "table"]
RECIPE = "timestamp,actual_q,robot_mode"


@pytest.fixture(scope="module")
def packages(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("input") / "packages.bin"
    path.write_bytes(b"".join(rtde_packages(20_000)))  # about 1 MB of output in any format
    return path


@pytest.fixture
def filling_disk(tmp_path: Path) -> Iterator[Path]:
    """A 384 kB tmpfs with 60 kB left; skipped only where this process may not mount one."""
    where = tmp_path / "disk"
    where.mkdir()
    name = f"rtde-spec-{uuid.uuid4().hex[:8]}"
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=384k", name, str(where)], capture_output=True
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.decode().strip()}")
    try:
        stat = os.statvfs(where)
        (where / "filler").write_bytes(b"\0" * (stat.f_bavail * stat.f_frsize - 60_000))
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], check=False)


def decode(packages: Path, out: Path, fmt: str) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "rtde_spec", "decode", str(packages), "--recipe", RECIPE]
    return subprocess.run(
        [*command, "--format", fmt, "-o", str(out)], capture_output=True, text=True, timeout=300
    )


@pytest.mark.parametrize("fmt", FORMATS)
def test_decode_on_a_filling_disk_keeps_the_existing_file(
    packages: Path, filling_disk: Path, fmt: str
) -> None:
    out = filling_disk / f"decoded.{fmt}"
    out.write_bytes(b"the earlier output\n")
    result = decode(packages, out, fmt)
    assert result.returncode == 1, result.stderr
    assert f"file {out}: writing failed: the disk is full" in result.stderr, result.stderr
    assert "the file that was there is as it was" in result.stderr
    assert "Errno" not in result.stderr and "Traceback" not in result.stderr
    assert out.read_bytes() == b"the earlier output\n"
    assert temp_files(filling_disk) == []


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full on this system")
@pytest.mark.parametrize("fmt", FORMATS)
def test_decode_to_dev_full_names_it(packages: Path, fmt: str) -> None:
    result = decode(packages, Path("/dev/full"), fmt)
    assert result.returncode == 1, result.stderr
    assert result.stderr.strip() == "error: file /dev/full: writing failed: the disk is full", result.stderr
