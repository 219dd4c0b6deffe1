"""`rtde-spec serve` stops on SIGTERM and SIGHUP, however many come and whatever its clients do.

A service manager, `docker stop` or `kill` sends SIGTERM; a closed terminal SIGHUP; scripts and
supervisors often send them twice (the process and its group). The server runs every port on
one asyncio loop, so a stop signal must reach it as a loop callback: raised as an exception
wherever the loop stood, it could lose a task's next step, and asyncio.run then waited for
that task forever (seen once in five stops of a benchmark's emulator).
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from rtde_spec import RtdeClient

HOST = "127.0.0.95"
PORTS = ("rtde", "primary", "secondary", "realtime", "dashboard")
pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="POSIX signals")


def serve() -> tuple[subprocess.Popen[str], dict[str, int]]:
    every = [arg for name in PORTS for arg in (f"--{name}-port", "0")]
    proc = subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "serve", "--host", HOST, *every],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None
    line = proc.stdout.readline()  # "emulating controller 5.15.0 on HOST: rtde N, primary N, ..."
    assert line, proc.communicate(timeout=10)
    return proc, {name: int(port) for name, port in re.findall(r"(\w+) (\d+)", line.split(": ", 1)[1])}


@contextmanager
def busy_clients(ports: dict[str, int]) -> Iterator[list[int]]:
    """An RTDE client at 500 Hz and readers on the state ports, until the server goes; yields
    the count of RTDE packages each time it is read."""
    done = threading.Event()
    received = [0]

    def rtde() -> None:
        try:
            with RtdeClient(HOST, ports["rtde"]) as client:
                client.setup_outputs(["timestamp", "actual_q", "actual_TCP_pose"], 500)
                client.start()
                for _ in client:
                    received[0] += 1
                    if done.is_set():
                        return
        except Exception:  # the server went away (the client's errors for a closed connection)
            return

    def reader(port: int) -> None:
        try:
            with socket.create_connection((HOST, port), timeout=10) as sock:
                while not done.is_set() and sock.recv(65536):
                    pass
        except OSError:
            return

    threads = [threading.Thread(target=rtde, daemon=True)]
    threads += [
        threading.Thread(target=reader, args=(ports[n],), daemon=True) for n in ("secondary", "realtime")
    ]
    for thread in threads:
        thread.start()
    try:
        yield received
    finally:
        done.set()
        for thread in threads:
            thread.join(10)


def wait_for_packages(received: list[int], at_least: int = 100) -> None:
    deadline = time.monotonic() + 10
    while received[0] < at_least:
        assert time.monotonic() < deadline, f"only {received[0]} RTDE packages in 10 s"
        time.sleep(0.01)


def assert_stopped_cleanly(proc: subprocess.Popen[str], ports: dict[str, int]) -> None:
    try:
        _, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        pytest.fail(f"serve still ran 10 s after the stop signals: {err[-2000:]}")
    assert proc.returncode == 0, err[-2000:]
    assert "Traceback" not in err, err[-2000:]
    for port in ports.values():  # every port closed with it
        with pytest.raises(ConnectionRefusedError), socket.create_connection((HOST, port), timeout=5):
            pass


@pytest.mark.parametrize("name", ["SIGTERM", "SIGHUP"])
def test_a_stop_signal_stops_serve_while_clients_stream(name: str) -> None:
    proc, ports = serve()
    with busy_clients(ports) as received:
        wait_for_packages(received)
        proc.send_signal(getattr(signal, name))
        assert_stopped_cleanly(proc, ports)


def test_a_burst_of_stop_signals_stops_serve_once_and_cleanly() -> None:
    """Forty signals in a row, the later ones while it stops: each one only asks it to stop."""
    proc, ports = serve()
    with busy_clients(ports) as received:
        wait_for_packages(received)
        for n in range(40):
            os.kill(proc.pid, signal.SIGTERM if n % 2 == 0 else signal.SIGHUP)
        assert_stopped_cleanly(proc, ports)


CHILD = """
import signal, sys, threading, time
from rtde_spec.cli import main, stop_signals

def look():
    # the default at first, then the CLI's, then (once serve's loop runs) the loop's
    cli = (signal.SIG_DFL, stop_signals.interrupt)
    deadline = time.monotonic() + 20
    while signal.getsignal(signal.SIGTERM) in cli and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.5)  # serving by then
    handler = signal.getsignal(signal.SIGTERM)
    print("handler", "the CLI's" if handler is stop_signals.interrupt else "the loop's", flush=True)
    signal.raise_signal(signal.SIGTERM)

threading.Thread(target=look, daemon=True).start()
sys.exit(main.main(sys.argv[1:]))
"""


def test_while_serving_a_stop_signal_is_the_event_loops_not_an_exception() -> None:
    """The CLI's own handler raises KeyboardInterrupt where the program stands; while `serve`
    runs its loop the loop takes the signal instead (and gives the CLI's back after)."""
    every = [arg for name in PORTS for arg in (f"--{name}-port", "0")]
    done = subprocess.run(
        [sys.executable, "-c", CHILD, "serve", "--host", HOST, *every],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "handler the loop's" in done.stdout, done.stdout
    assert "Traceback" not in done.stderr, done.stderr[-2000:]


@pytest.mark.slow  # 12 starts of the emulator, ~11 s
def test_stop_signals_at_random_moments_of_the_control_loop() -> None:
    """Stopped 12 times at moments spread over a 500 Hz step, clients streaming each time."""
    for n in range(12):
        proc, ports = serve()
        with busy_clients(ports) as received:
            wait_for_packages(received, at_least=20)
            time.sleep(n * 0.00017)  # 12 points across one 2 ms step
            proc.send_signal(signal.SIGTERM)
            assert_stopped_cleanly(proc, ports)
