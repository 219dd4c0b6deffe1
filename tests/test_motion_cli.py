"""Our own tools show the arm move (issue 20.6): `demo` records a motion program by default, `watch
--every` prints joints that change one way along a movej, `record` writes them and `plot` draws
them. Each runs as a user runs it (a subprocess), against `rtde-spec serve` in its own process.
"""

from __future__ import annotations

import csv
import itertools
import re
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rtde_spec.emulator.controller.model import HOME_Q

TARGET = [0.5, -1.4, 1.4, -1.6, -1.5, 0.3]
MOVEJ = f"movej({TARGET}, a=2.0, v=1.0)\n"


def command() -> list[str]:
    exe = shutil.which("rtde-spec")
    return [exe] if exe else [sys.executable, "-m", "rtde_spec"]


def serve(host: str) -> tuple[subprocess.Popen[str], dict[str, int]]:
    proc = subprocess.Popen(
        [*command(), "serve", "--host", host, "--rtde-port", "0", "--primary-port", "0",
         "--secondary-port", "0", "--dashboard-port", "-1", "--realtime-port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert proc.stdout is not None
    line = proc.stdout.readline()  # "emulating controller 5.15.0 on HOST: rtde N, primary N, ..."
    ports = {name: int(port) for name, port in re.findall(r"(\w+) (\d+)", line.split(":", 1)[-1])}
    assert "primary" in ports, line
    return proc, ports


def monotone(values: list[float]) -> bool:
    """One way from the first value to the last (either direction)."""
    up = values[-1] >= values[0]
    return all((b >= a - 1e-12) if up else (b <= a + 1e-12) for a, b in itertools.pairwise(values))


@pytest.mark.slow  # the README's demo block runs it in the plain run too: CI runs it
def test_demo_records_a_moving_arm_in_seconds(tmp_path: Path) -> None:
    started = time.monotonic()
    result = subprocess.run([*command(), "demo", "-o", str(tmp_path)], capture_output=True, text=True)
    elapsed = time.monotonic() - started
    assert result.returncode == 0, result.stderr
    assert "movej" in result.stdout and "Plot:" in result.stdout
    with open(tmp_path / "joints.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    base = [float(r["actual_q_0"]) for r in rows]
    assert base[0] == pytest.approx(0.0) and max(base) == pytest.approx(0.6, abs=1e-3)  # its movej
    peak = base.index(max(base))
    assert monotone(base[: peak + 1]) and sum(b > a for a, b in itertools.pairwise(base)) > 50
    assert base[-1] == pytest.approx(0.0, abs=1e-6)  # home again
    assert (tmp_path / "joints.png").stat().st_size > 10_000
    assert elapsed < 60  # about 5 s on an idle machine; generous for a loaded one


@pytest.mark.slow  # seconds of real time (recording, a 5 s rule, a move): CI runs it
def test_watch_every_shows_the_joints_move_one_way_along_a_movej(tmp_path: Path) -> None:
    script = tmp_path / "move.script"
    script.write_text(MOVEJ)
    proc, ports = serve("127.0.0.42")
    try:
        result = subprocess.run(
            [*command(), "watch", "--host", "127.0.0.42", "--port", str(ports["primary"]), "--every",
             "--duration", "4", "--script", str(script)],
            capture_output=True, text=True, timeout=60,
        )  # fmt: skip
    finally:
        proc.terminate()
        proc.wait(10)
    assert result.returncode == 0, result.stderr
    joints = [
        [float(v) for v in m.group(1).split()]
        for m in re.finditer(r"pose\s+q \[rad\] ([-\d. ]+) ·", result.stdout)
    ]
    assert len(joints) >= 20  # 10 Robot States a second
    base = [q[0] for q in joints]
    assert base[-1] == pytest.approx(TARGET[0], abs=1e-3) and monotone(base)
    assert len({round(b, 4) for b in base}) >= 8  # many values on the way: it moved, not jumped


@pytest.mark.slow  # seconds of real time (recording, a 5 s rule, a move): CI runs it
def recording(folder: Path, name: str, timeout: float = 30.0) -> None:
    """Wait until `record -o NAME` has written rows (more than its header line; to the file, in
    place from its first rows, or beside it): a fixed sleep was too short on a loaded machine,
    and the move began first."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        parts = [*folder.glob(name), *folder.glob(f".{name}*")]
        if any(part.stat().st_size > 200 for part in parts if part.exists()):
            return
        time.sleep(0.05)
    raise AssertionError(f"record wrote no rows in {timeout} s: {sorted(p.name for p in folder.iterdir())}")


def test_record_and_plot_show_the_move(tmp_path: Path) -> None:
    out, png = tmp_path / "joints.csv", tmp_path / "joints.png"
    proc, ports = serve("127.0.0.43")
    try:
        recorder = subprocess.Popen(
            [*command(), "record", "--host", "127.0.0.43", "--port", str(ports["rtde"]), "--fields",
             "timestamp,actual_q,actual_qd", "--frequency", "125", "--duration", "4", "-o", str(out)],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        )  # fmt: skip
        recording(tmp_path, "joints.csv")  # rows written: the move starts after the first of them
        with socket.create_connection(("127.0.0.43", ports["realtime"])) as sock:  # URScript on 30003
            sock.sendall(MOVEJ.encode())
            _, err = recorder.communicate(timeout=60)
    finally:
        proc.terminate()
        proc.wait(10)
    assert recorder.returncode == 0, err
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    base = [float(r["actual_q_0"]) for r in rows]
    assert base[0] == pytest.approx(HOME_Q[0]) and base[-1] == pytest.approx(TARGET[0], abs=1e-9)
    assert monotone(base)
    moving = [b for b in base if 1e-6 < b < TARGET[0] - 1e-6]
    assert len(moving) >= 60  # the move at 125 Hz
    assert max(float(r["actual_qd_0"]) for r in rows) > 0.3
    plotted = subprocess.run(
        [*command(), "plot", str(out), "actual_q", "-o", str(png)], capture_output=True, text=True
    )
    assert plotted.returncode == 0, plotted.stderr
    assert png.stat().st_size > 10_000
