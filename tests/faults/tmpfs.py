"""A small tmpfs of a test's own: the real full disk (root can mount one; CI runs as root)."""

from __future__ import annotations

import os
import subprocess
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest


@contextmanager
def mounted_tmpfs(where: Path, options: str) -> Iterator[Path]:
    """`where` as a tmpfs with mount `options` ("size=384k", "size=4m,nr_inodes=48"); skipped only
    where this process may not mount one."""
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", options, f"rtde-spec-{uuid.uuid4().hex[:8]}", str(where)],
        capture_output=True,
        text=True,
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.strip()}")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], check=False)


def fill(disk: Path, leave: int = 0) -> None:
    """Leave about `leave` bytes free on `disk` (nothing at all with 0)."""
    stat = os.statvfs(disk)
    todo = max(0, stat.f_bavail * stat.f_frsize - leave) if leave else 1 << 40
    block = b"\0" * 65536
    fd = os.open(disk / "filler", os.O_WRONLY | os.O_CREAT | os.O_APPEND)
    try:
        while todo > 0:
            todo -= os.write(fd, block[: min(todo, len(block))])
    except OSError:  # full: what was asked
        pass
    finally:
        os.close(fd)
