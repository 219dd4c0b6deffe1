"""The controller's fixed ports are the machine's: tests that need them take turns with every run on it.

ur_rtde, urx and the docs' commands reach a controller on its own ports (29999, 30001-30004), so
some modules serve them on a loopback address (`pytest.mark.fixed_ports("127.0.0.71")`). Loopback
is the machine's, not the test run's: two checkouts tested at once (or a `rtde-spec serve` left
running) hold the same address and port, and the later one was refused ("address already in
use" on 127.0.0.1:30004 and 127.0.0.71:30004 in full runs). Such a module holds a lock per
address for its whole run (a file lock in the temp folder, which every run on the machine sees),
then waits until the ports are free (a process that takes no lock: an older checkout's run, a
user's emulator); after `WAIT` seconds it fails naming who holds them.
"""

from __future__ import annotations

import contextlib
import errno
import os
import socket
import subprocess
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import pytest

try:
    import fcntl
except ImportError:  # not on Windows: the ports are only waited for
    fcntl = None  # type: ignore[assignment]

CONTROLLER_PORTS = (29999, 30001, 30002, 30003, 30004)
WAIT = 600.0  # s: another run's module holding the ports ends well within it


def lock_path(host: str) -> Path:
    return Path(tempfile.gettempdir()) / f"rtde_spec-fixed-ports-{host}.lock"


def _take(file: IO[str], host: str, deadline: float) -> None:
    if fcntl is None:
        return
    while True:
        try:
            fcntl.flock(file.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            break
        except BlockingIOError:
            if time.monotonic() > deadline:
                file.seek(0)
                pytest.fail(f"{host}'s fixed ports stay taken by another test run: {file.read() or '?'} "
                            f"(lock {lock_path(host)})", pytrace=False)  # fmt: skip
            time.sleep(0.5)
    file.seek(0)
    file.truncate()
    file.write(f"pid {os.getpid()} in {os.getcwd()}")
    file.flush()


def is_free(host: str, port: int) -> bool:
    """Whether a server could listen there now (as the emulator binds: TIME_WAIT does not count)."""
    with socket.socket() as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, port))
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                return False
            raise
    return True


def holders(host: str, ports: list[int]) -> str:
    """Who listens on these ports, as `ss` says (pid and folder), for the failure message."""
    try:
        out = subprocess.run(["ss", "-Hltnp"], capture_output=True, text=True, timeout=10).stdout
    except (OSError, subprocess.TimeoutExpired):
        return "(ss not available)"
    lines = []
    for line in out.splitlines():
        if any(
            f"{host}:{port} " in line or f"0.0.0.0:{port} " in line or f"*:{port} " in line for port in ports
        ):
            pid = line.partition("pid=")[2].partition(",")[0]
            where = os.path.realpath(f"/proc/{pid}/cwd") if pid else "?"
            lines.append(f"{line.split()[3]} pid {pid or '?'} in {where}")
    return "; ".join(lines) or "nobody now"


def wait_until_free(host: str, ports: tuple[int, ...] = CONTROLLER_PORTS, wait: float = WAIT) -> None:
    deadline = time.monotonic() + wait
    while True:
        busy = [port for port in ports if not is_free(host, port)]
        if not busy:
            return
        if time.monotonic() > deadline:
            pytest.fail(
                f"{host}: ports {busy} stay in use for {wait:.0f} s: {holders(host, busy)}", pytrace=False
            )
        time.sleep(0.5)


@contextlib.contextmanager
def fixed_ports(*hosts: str, ports: tuple[int, ...] = CONTROLLER_PORTS, wait: float = WAIT) -> Iterator[None]:
    """Hold these addresses' fixed ports: their locks (in sorted order: no two runs deadlock), then free."""
    deadline = time.monotonic() + wait
    with contextlib.ExitStack() as stack:
        for host in sorted(set(hosts)):
            file = stack.enter_context(open(lock_path(host), "a+", encoding="utf-8"))
            _take(file, host, deadline)
            if fcntl is not None:
                stack.callback(fcntl.flock, file.fileno(), fcntl.LOCK_UN)
            stack.callback(file.truncate, 0)
        for host in hosts:
            wait_until_free(host, ports, max(1.0, deadline - time.monotonic()))
        yield
