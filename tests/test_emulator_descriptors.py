"""`rtde-spec serve` out of file descriptors: it keeps serving the clients it has, closes the ones
it cannot serve at once (not left waiting for a reply), logs one line each way and no
traceback, and serves again once descriptors free up. A real limit (RLIMIT_NOFILE) on a real
`rtde-spec serve` process, real sockets on loopback."""

from __future__ import annotations

import os
import re
import select
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec._generated import rtde_models as gen

resource = pytest.importorskip("resource")
pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc/PID/fd and prlimit")

HOST = "127.0.0.3"  # apart from the tests on 127.0.0.1; every port 0, so none collide


class Served:
    """A `rtde-spec serve` subprocess under a descriptor limit: its pid, ports and log."""

    def __init__(self, proc: subprocess.Popen[str], ports: dict[str, int], log: Path) -> None:
        self.proc, self.ports, self.log = proc, ports, log

    def open_fds(self) -> int:
        return len(os.listdir(f"/proc/{self.proc.pid}/fd"))

    def limit(self, n: int) -> None:
        """Set the running server's soft descriptor limit (`ulimit -n`); lower than it holds is
        allowed: none more opens. The hard limit stays, so raising it again needs no privilege."""
        _, hard = resource.prlimit(self.proc.pid, resource.RLIMIT_NOFILE)
        resource.prlimit(self.proc.pid, resource.RLIMIT_NOFILE, (n, hard))

    def text(self) -> str:
        return self.log.read_text(errors="replace")


@pytest.fixture
def serve(tmp_path: Path) -> Iterator[object]:
    started: list[subprocess.Popen[str]] = []

    def start(limit: int | None) -> Served:
        log = tmp_path / f"serve{len(started)}.log"

        def low() -> None:  # in the child, before it runs: the limit it is born with
            if limit is not None:
                _, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
                resource.setrlimit(resource.RLIMIT_NOFILE, (limit, hard))

        cmd = [
            sys.executable, "-m", "rtde_spec.cli", "serve", "--host", HOST, "--rtde-port", "0",
            "--primary-port", "0", "--secondary-port", "0", "--realtime-port", "-1", "--dashboard-port", "-1",
        ]  # fmt: skip
        with log.open("w") as err:
            proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=err, text=True, preexec_fn=low)
        started.append(proc)
        assert proc.stdout is not None
        ready, _, _ = select.select([proc.stdout], [], [], 60)
        assert ready, "serve printed no ports within 60 s"
        line = proc.stdout.readline()
        assert "emulating controller" in line, line + log.read_text()
        ports = {name: int(port) for name, port in re.findall(r"(\w+) (\d+)", line.split(": ", 1)[1])}
        return Served(proc, ports, log)

    yield start
    for proc in started:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if proc.stdout is not None:
            proc.stdout.close()


def fate(sock: socket.socket, seconds: float) -> str:
    """ "served" (bytes came), "closed" (the server closed it) or "waiting" (neither, within `seconds`)."""
    sock.settimeout(seconds)
    try:
        return "served" if sock.recv(4096) else "closed"
    except TimeoutError:
        return "waiting"
    except OSError:
        return "closed"


def primary(port: int) -> socket.socket:
    """A primary-port client: the server sends it state at once, unasked."""
    return socket.create_connection((HOST, port), timeout=5)


def rtde_answers(port: int) -> bool:
    with socket.create_connection((HOST, port), timeout=5) as sock:
        sock.sendall(gen.RequestProtocolVersion(protocol_version=2).to_bytes())
        return fate(sock, 5) == "served"


def limit_lines(text: str) -> list[str]:
    return [line for line in text.splitlines() if "file descriptors" in line]


def assert_calm(text: str, most: int) -> None:
    """No traceback, no asyncio error, and at most `most` lines about the limit."""
    assert "Traceback" not in text and "out of system resource" not in text, text[:3000]
    assert 1 <= len(limit_lines(text)) <= most, text[:3000]


def test_six_clients_on_a_few_descriptors_are_served_or_closed_at_once_and_it_recovers(serve) -> None:  # type: ignore[no-untyped-def]
    emu = serve(None)
    limit = emu.open_fds() + 2
    emu.limit(limit)  # room for two clients, as `ulimit -n` that low would leave
    clients = [primary(emu.ports["primary"]) for _ in range(6)]
    began = time.monotonic()
    fates = [fate(sock, 3) for sock in clients]
    assert fates.count("served") == 2 and fates.count("closed") == 4, fates  # none left waiting
    assert time.monotonic() - began < 6
    time.sleep(1.0)  # the two served stay served: more state comes
    served = [sock for sock, f in zip(clients, fates, strict=True) if f == "served"]
    assert all(fate(sock, 2) == "served" for sock in served)
    assert emu.proc.poll() is None
    for sock in clients:
        sock.close()
    time.sleep(0.5)  # the server sees the two go
    assert rtde_answers(emu.ports["rtde"])  # descriptors free again: served as ever
    again = primary(emu.ports["primary"])
    assert fate(again, 3) == "served"
    again.close()
    assert emu.proc.poll() is None
    text = emu.text()
    assert_calm(text, 2)
    first, last = limit_lines(text)[0], limit_lines(text)[-1]
    assert f"ulimit -n {limit}" in first and "refused" in first and "free again" in last, text


def test_with_no_descriptor_free_a_client_is_closed_not_kept_waiting_and_a_flood_stays_quiet(serve) -> None:  # type: ignore[no-untyped-def]
    emu = serve(None)
    held = emu.open_fds()
    emu.limit(held)  # not one free
    for _ in range(3):
        flood = [primary(emu.ports[name]) for name in ("primary", "secondary", "rtde") for _ in range(10)]
        assert [fate(sock, 3) for sock in flood] == ["closed"] * 30
        for sock in flood:
            sock.close()
    time.sleep(1.5)
    assert emu.proc.poll() is None
    emu.limit(held + 4)  # descriptors again (as if another program of the process closed some)
    assert rtde_answers(emu.ports["rtde"])
    text = emu.text()
    assert_calm(text, 2)
    assert f"ulimit -n {held}" in limit_lines(text)[0], text


def test_born_with_no_descriptor_to_spare_it_says_so_once_and_serves_when_given_some(serve) -> None:  # type: ignore[no-untyped-def]
    probe = serve(None)
    needed = probe.open_fds() - 1  # what it holds but the reserve
    probe.proc.send_signal(signal.SIGINT)
    probe.proc.wait(10)
    emu = serve(needed)
    waiting = primary(emu.ports["primary"])
    assert fate(waiting, 1.5) == "waiting"  # nothing to accept nor refuse it with; no spinning
    assert emu.proc.poll() is None
    emu.limit(needed + 3)
    assert fate(waiting, 5) == "served"  # the client that waited is served once one is free
    waiting.close()
    assert rtde_answers(emu.ports["rtde"])
    text = emu.text()
    assert_calm(text, 3)
    assert f"ulimit -n {needed}" in limit_lines(text)[0], text
