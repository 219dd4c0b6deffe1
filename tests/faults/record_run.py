"""`rtde-spec record` as a real subprocess against the emulator, and what its files hold afterwards.

The emulator runs in the test process on port 0 with `skip_after=None` (every control
step is sent, late if the machine stalls), so the timestamps of every row it sent are
consecutive: a gap in a file is a row lost by the recorder.
"""

from __future__ import annotations

import csv
import itertools
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from rtde_spec import EmulatorConfig, EmulatorThread

FIELDS = "timestamp,actual_q"
HZ = 500
COLUMNS = ["timestamp", *(f"actual_q_{i}" for i in range(6))]


def emulator() -> Iterator[EmulatorThread]:
    """For a module-scoped fixture: an emulator that sends every step."""
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=0,
        secondary_port=0,
        skip_after=None,
        realtime_port=None,
        dashboard_port=None,
    )
    emu = EmulatorThread(config).start()
    yield emu
    emu.stop()


def start(emu: EmulatorThread, out: Path, *extra: str, fields: str = FIELDS) -> subprocess.Popen[str]:
    """`python -m rtde_spec record ... -o out`; `os.kill(pid)` signals it alone.

    Not in a session of its own: on Linux each session is a scheduler autogroup, and with CPU
    hogs in the test run's session the recorder's group got no CPU for seconds (from 1.3 s to
    5.4 s of one recording), missing the tests' allowances (rows in 2.5 s, two parts in 6 s, its
    own 5 s reply timeout); in the test run's session it keeps up under the same hogs."""
    command = [sys.executable, "-m", "rtde_spec", "record", "--host", "127.0.0.1"]
    command += ["--port", str(emu.ports["rtde"]), "--fields", fields, "--frequency", str(HZ), "-o", str(out)]
    return subprocess.Popen([*command, *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def run(
    emu: EmulatorThread, out: Path, *extra: str, fields: str = FIELDS
) -> subprocess.CompletedProcess[str]:
    process = start(emu, out, *extra, fields=fields)
    stdout, stderr = process.communicate(timeout=120)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def streaming(emu: EmulatorThread) -> int:
    """Started RTDE clients the emulator is sending data packages to."""
    return sum(1 for c in list(emu.emulator.rtde.connections) if c.started)


def record_then_signal(
    emu: EmulatorThread, out: Path, sig: int, seconds: float, *extra: str
) -> tuple[subprocess.CompletedProcess[str], float]:
    """Record for `seconds` after the data starts flowing, send `sig`; the result and the
    controller time at the signal."""
    process = start(emu, out, *extra)
    deadline = time.monotonic() + 90  # a loaded machine starts Python slowly
    while streaming(emu) == 0:
        if process.poll() is not None or time.monotonic() > deadline:
            process.kill()
            _, stderr = process.communicate()
            raise AssertionError(f"the recorder never started: {stderr}")
        time.sleep(0.05)
    time.sleep(seconds)
    sent_until = emu.model.time
    os.kill(process.pid, sig)
    stdout, stderr = process.communicate(timeout=120)
    deadline = time.monotonic() + 10  # the emulator notices the closed connection
    while streaming(emu) and time.monotonic() < deadline:
        time.sleep(0.05)
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr), sent_until


def steps(stamps: list[float]) -> set[int]:
    """The control steps between consecutive rows ({1} at 500 Hz when none is missing)."""
    return {round((b - a) * HZ) for a, b in itertools.pairwise(stamps)}


def csv_rows(path: Path) -> list[list[str]]:
    """Every row of a CSV recording, checked whole: the header, then complete lines of numbers."""
    text = path.read_text()
    assert text.endswith("\n"), f"{path.name} ends inside a line: {text[-80:]!r}"
    rows = list(csv.reader(text.splitlines()))
    assert rows[0] == COLUMNS, f"{path.name}: header {rows[0]}"
    for row in rows[1:]:
        assert len(row) == len(COLUMNS), f"{path.name}: an incomplete line {row}"
        [float(v) for v in row]
    return rows[1:]


def temp_files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".part-" in p.name)


def parts(folder: Path, stem: str, suffix: str) -> list[Path]:
    return sorted(folder.glob(f"{stem}_[0-9][0-9][0-9][0-9]{suffix}"))


SIGHUP = getattr(signal, "SIGHUP", signal.SIGTERM)
