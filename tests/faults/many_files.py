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
import json, os, resource, sys, threading, time
limit = int(sys.argv[1])
if limit:
    resource.setrlimit(resource.RLIMIT_NOFILE, (limit, limit))
peak = [0]
def sample():
    while True:
        peak[0] = max(peak[0], len(os.listdir("/proc/self/fd")) - 1)  # less the listing's own
        time.sleep(0.001)
if os.path.isdir("/proc/self/fd"):
    threading.Thread(target=sample, daemon=True).start()
from rtde_spec.cli.main import main
code = main(sys.argv[2:])
print(json.dumps({"peak_descriptors": peak[0]}), file=sys.stderr)
sys.exit(code)
"""

PEAK = '{"peak_descriptors": '


def run_limited(limit: int, *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """`rtde-spec ARGS` in a child whose descriptor limit (soft and hard) is `limit` (0: as it is);
    its last stderr line is the most descriptors it held at once (sampled every millisecond)."""
    return subprocess.run(
        [sys.executable, "-c", LIMITED, str(limit), *args],
        capture_output=True, text=True, cwd=cwd, timeout=600,
    )  # fmt: skip


def peak_descriptors(stderr: str) -> int | None:
    """The figure `run_limited`'s child printed last, if it got that far."""
    import json

    lines = [line for line in stderr.splitlines() if line.startswith(PEAK)]
    return int(json.loads(lines[-1])["peak_descriptors"]) if lines else None
