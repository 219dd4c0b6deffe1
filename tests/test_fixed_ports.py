"""The controller's fixed ports: what `EmulatorConfig()` serves (what `serve` does), a failed start
closing what it opened, and test runs on one machine taking turns for them (tests/fixed_ports.py)."""

from __future__ import annotations

import dataclasses
import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.cli.conventions import leaf_parsers
from rtde_spec.cli.main import build_parser

from .fixed_ports import fixed_ports, is_free, lock_path

HOST = "127.0.0.94"  # an address no other module serves on
ROOT = Path(__file__).resolve().parents[1]
SERVE_PORTS = {"rtde": 30004, "primary": 30001, "secondary": 30002, "realtime": 30003, "dashboard": 29999}
# serve's interpreter socket (e-Series 5.10 on); the library's plain config leaves it off, as the
# configurations written before it name each port they serve (they would all take 127.0.0.1:30020)
SERVE_ONLY = {"interpreter": 30020}


def serve_defaults() -> dict[str, int]:
    """The ports `rtde-spec serve` listens on when given none, as its help says them."""
    (serve,) = [parser for words, parser in leaf_parsers(build_parser()) if words == "serve"]
    text = " ".join(serve.format_help().split())
    found = re.findall(r"--(\w+)-port PORT [^(]*\(default: [^0-9)]*(\d+)", text)
    return {name: int(port) for name, port in found}


def test_emulator_config_defaults_are_the_ports_serve_serves() -> None:
    assert serve_defaults() == {**SERVE_PORTS, **SERVE_ONLY}  # what serve's help says ...
    config = EmulatorConfig()
    served = {f.name.removesuffix("_port"): getattr(config, f.name) for f in dataclasses.fields(config)
              if f.name.endswith("_port") and getattr(config, f.name) is not None}  # fmt: skip
    assert served == SERVE_PORTS  # ... the library's plain config serves too
    moved = EmulatorConfig(rtde_port=0)  # the example: RTDE moves, the others stay
    kept = (moved.primary_port, moved.secondary_port, moved.realtime_port, moved.dashboard_port)
    assert moved.rtde_port == 0 and kept == (30001, 30002, 30003, 29999)


def test_every_port_serve_serves_moves_to_a_free_one_in_an_emulator_thread_too() -> None:
    every = [arg for name in {**SERVE_PORTS, **SERVE_ONLY} for arg in (f"--{name}-port", "0")]
    proc = subprocess.Popen([sys.executable, "-m", "rtde_spec", "serve", "--host", HOST, *every],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)  # fmt: skip
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()  # "emulating controller 5.15.0 on HOST: rtde N, primary N, ..."
    finally:
        proc.terminate()
        proc.wait(20)
    by_serve = dict(re.findall(r"(\w+) (\d+)", line.split(": ", 1)[1]))
    ports = {f"{name}_port": 0 for name in {**SERVE_PORTS, **SERVE_ONLY}}
    with EmulatorThread(EmulatorConfig(host=HOST, **ports)) as emu:  # type: ignore[arg-type]
        assert set(emu.ports) == set(by_serve) == {*SERVE_PORTS, *SERVE_ONLY}
        assert not set(emu.ports.values()) & {*SERVE_PORTS.values(), *SERVE_ONLY.values()}  # free ports
        with socket.create_connection((HOST, emu.ports["dashboard"]), timeout=5) as dashboard:
            assert dashboard.makefile("r").readline().startswith("Connected: Universal Robots Dashboard")


def test_a_failed_start_closes_the_ports_it_had_opened() -> None:
    with socket.create_server((HOST, 0)) as taken:
        config = EmulatorConfig(
            host=HOST, rtde_port=0, primary_port=0, secondary_port=None, realtime_port=None,
            dashboard_port=taken.getsockname()[1],
        )  # fmt: skip
        thread = EmulatorThread(config)
        with pytest.raises(OSError, match="address already in use"):
            thread.start()
        opened = dict(thread.ports)  # RTDE and primary listened before the dashboard failed ...
        assert set(opened) == {"rtde", "primary"}
        assert all(is_free(HOST, port) for port in opened.values())  # ... and listen no more


def test_a_second_run_waits_until_the_first_gives_the_ports_back() -> None:
    with socket.socket() as probe:  # a port no one uses
        probe.bind((HOST, 0))
        port = probe.getsockname()[1]
    other = (
        "import time\nfrom tests.fixed_ports import fixed_ports\nprint('trying', flush=True)\n"
        f"with fixed_ports({HOST!r}, ports=({port},), wait=30):\n    print(time.time())\n"
    )
    with fixed_ports(HOST, ports=(port,), wait=10):
        assert "pid" in lock_path(HOST).read_text()  # who holds them, for a run that waits too long
        command = [sys.executable, "-c", other]
        proc = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, cwd=str(ROOT))
        assert proc.stdout is not None and proc.stdout.readline() == "trying\n"
        time.sleep(1.0)
        assert proc.poll() is None  # waiting its turn
        released = time.time()
    out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0 and float(out) >= released


def test_a_port_held_by_a_process_taking_no_turns_is_waited_for() -> None:
    holder = socket.create_server((HOST, 0))  # as an older checkout's run or a user's emulator
    port = holder.getsockname()[1]
    threading.Timer(1.0, holder.close).start()
    start = time.monotonic()
    with fixed_ports(HOST, ports=(port,), wait=20):
        assert is_free(HOST, port)
    assert time.monotonic() - start >= 0.9
