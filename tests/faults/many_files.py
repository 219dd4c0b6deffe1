"""Captures that make many output files, and runs of the real CLI under a descriptor limit.

A capture of N robots x days gives a file per table, robot and day: the case that ran out
of descriptors. Shared by tests/faults/ and benchmarks/faults.py.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.capture_files import Conversation, rtde_packages, rtde_setup, write

DAY = 86_400.0


def fleet_capture(path: Path, robots: int, days: int = 3, per_day: int = 4) -> Path:
    """`robots` robots recorded on `days` days, a connection a day: per robot and day an
    rtde_setup and an rtde_outputs_1 file (robots x days x 2 files)."""
    packages = rtde_packages(per_day)
    conversations = []
    for i in range(robots):
        server = (f"10.1.{i // 250}.{i % 250 + 1}", 30004)
        for day in range(days):
            client = (f"10.2.{i // 250}.{i % 250 + 1}", 40000 + day)
            conv = Conversation(client, server, time=1_700_000_000 + day * DAY + i * 0.01)
            rtde_setup(conv)
            for package in packages:
                conv.send("server", package)
            conversations.append(conv)
    return write(path, conversations)


LIMITED = """\
import resource, sys
limit = int(sys.argv[1])
resource.setrlimit(resource.RLIMIT_NOFILE, (limit, limit))
from rtde_spec.cli.main import main
sys.exit(main(sys.argv[2:]))
"""


def run_limited(limit: int, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """`rtde-spec ARGS` in a child whose descriptor limit (soft and hard) is `limit`."""
    return subprocess.run(
        [sys.executable, "-c", LIMITED, str(limit), *args],
        capture_output=True, text=True, cwd=cwd, timeout=600,
    )  # fmt: skip
