"""Hostile URScript programs end in the controller's errors while every port keeps answering.

The programs of issue 26 (point 7), one after another on the primary port of an emulator running
in its own process: two 32-deep nested lists compared, a 3-deep list of 68,921 elements compared,
`norm` of a 26-deep list, one call spread over 64,000 lines, a program that keeps 1 MB more in
every step, a 10 MB program, and 500 connections sending scripts at once. Each ends in the
controller's runtime error (or the client is refused), within seconds; meanwhile an RTDE reader
misses no package (timestamp continuity) and never waits long for one, the dashboard answers
every request, and the emulator's memory stays bounded (read from /proc).
"""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from rtde_spec import PrimaryClient
from rtde_spec.emulator.urscript.interpreter import MEMORY_BUDGET
from tests.faults.test_emulator_hostile import GoodClient, PeakRss, rss
from tests.test_urscript_control import named, read_until

if not Path("/proc/self/status").exists():  # pragma: no cover - Linux CI
    pytest.skip("reads the emulator's memory from /proc", allow_module_level=True)

SERVER = """
import asyncio, sys
from rtde_spec.emulator.server import Emulator, EmulatorConfig
config = EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=None, dashboard_port=0,
                        realtime_port=None, skip_after=None)

async def main():
    emulator = Emulator(config)
    await emulator.start()
    print(emulator.ports["rtde"], emulator.ports["primary"], emulator.ports["dashboard"], flush=True)
    await asyncio.Event().wait()

asyncio.run(main())
"""

ROW = "[" + ", ".join(["1"] * 41) + "]"
PROGRAMS = [
    ("a = [1]\nb = [1]\n" + "a = [a, a]\nb = [b, b]\n" * 32 + "c = a == b\n", "arrays nest at most"),
    (
        f"r = {ROW}\ns = {ROW}\na = [" + ", ".join(["r"] * 41) + "]\nb = [" + ", ".join(["s"] * 41)
        + "]\nA = [" + ", ".join(["a"] * 41) + "]\nB = [" + ", ".join(["b"] * 41) + "]\nc = A == B\n",
        "elements",
    ),
    ("a = [1.0]\n" + "a = [a, a]\n" * 26 + "n = norm(a)\n", "arrays nest at most"),
    ("def big():\n  textmsg(1" + ",\n1" * 64_000 + ")\nend\n", "Runtime is too much behind"),
    (
        'def hog():\n  s = "xy"\n  i = 0\n  while i < 18:\n    s = str_cat(s, s)\n    i = i + 1\n  end\n'
        + "".join(f"  x{i} = str_cat(s, s)\n  sync()\n" for i in range(2 * (MEMORY_BUDGET >> 20)))
        + "end\n",
        "out of memory",
    ),
]  # fmt: skip


class TimedReader(GoodClient):
    """Every package, and the longest wait between two (the reader is served, not only counted)."""

    def __init__(self, port: int) -> None:
        super().__init__(port)
        self.longest = 0.0

    def run(self) -> None:
        threading.Thread(target=self._watch, daemon=True).start()
        super().run()

    def _watch(self) -> None:
        seen, since = 0, time.monotonic()
        while not self.stop.is_set():
            time.sleep(0.01)
            now = time.monotonic()
            if len(self.stamps) != seen:
                seen, since = len(self.stamps), now
            self.longest = max(self.longest, now - since)


class DashboardPinger(threading.Thread):
    """Asks `robotmode` every 50 ms on one connection; the longest wait for an answer."""

    def __init__(self, port: int) -> None:
        super().__init__(daemon=True)
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=10)
        self.reader = self.sock.makefile("r")
        self.reader.readline()  # the greeting
        self.longest = 0.0
        self.answers = 0
        self.error: str | None = None
        self.stop = threading.Event()

    def run(self) -> None:
        try:
            while not self.stop.is_set():
                asked = time.monotonic()
                self.sock.sendall(b"robotmode\n")
                reply = self.reader.readline()
                if not reply.startswith("Robotmode"):
                    self.error = f"answered {reply!r}"
                    return
                self.answers += 1
                self.longest = max(self.longest, time.monotonic() - asked)
                time.sleep(0.05)
        except OSError as exc:
            self.error = repr(exc)


def fault_after(client: PrimaryClient, script: str) -> str:
    client.send_script(script)
    got = read_until(client, lambda got: bool(named(got, "runtime_exception_message")), seconds=30)
    [fault] = named(got, "runtime_exception_message")
    return str(fault.runtime_exception_text_message)  # type: ignore[attr-defined]


def refused(port: int, data: bytes) -> bool:
    """Whether the emulator closes a connection that sends `data` (what it sends back is read away)."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    try:
        try:
            sock.sendall(data)
        except OSError:
            return True  # closed while we were still sending
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            if not sock.recv(65536):
                return True
        return False
    except OSError:
        return True
    finally:
        sock.close()


@pytest.mark.slow  # long end to end: CI runs it (RTDE_SPEC_SLOW=1), the fast loop does not
def test_hostile_programs_end_in_errors_while_rtde_and_the_dashboard_keep_answering() -> None:
    proc = subprocess.Popen([sys.executable, "-c", SERVER], stdout=subprocess.PIPE, text=True)
    try:
        rtde_port, primary_port, dashboard_port = map(int, proc.stdout.readline().split())  # type: ignore[union-attr]
        reader = TimedReader(rtde_port)
        pinger = DashboardPinger(dashboard_port)
        reader.start()
        pinger.start()
        time.sleep(1.0)
        sampler = PeakRss(proc.pid)
        texts = []
        with PrimaryClient("127.0.0.1", primary_port, timeout=10) as client:
            for script, _ in PROGRAMS:
                texts.append(fault_after(client, script))
        ten_mb = refused(primary_port, b"def big():\n" + b"  x = 1\n" * (10 << 17) + b"end\n")
        crowd = []
        for _ in range(500):  # 500 script connections at once: the port takes its limit, no more
            try:
                sock = socket.create_connection(("127.0.0.1", primary_port), timeout=10)
                sock.sendall(b'textmsg("hello")\n')
                crowd.append(sock)
            except OSError:
                pass
        time.sleep(2.0)
        closed = 0
        for sock in crowd:
            sock.setblocking(False)
            try:
                while True:
                    data = sock.recv(65536)
                    if not data:
                        closed += 1
                        break
            except BlockingIOError:
                pass
            except OSError:
                closed += 1
            sock.close()
        time.sleep(1.0)
        sampler.stop()
        final = rss(proc.pid)
        reader.stop.set()
        pinger.stop.set()
        reader.join(10)
        pinger.join(10)
    finally:
        proc.kill()
        proc.wait(10)
    report = (
        f"faults {texts}; 10 MB refused {ten_mb}; crowd closed {closed}/500; "
        f"reader missed {reader.missed()}, "
        f"longest wait {reader.longest:.2f} s, error {reader.error}; dashboard answers {pinger.answers}, "
        f"longest {pinger.longest:.2f} s, error {pinger.error}; "
        f"RSS +{(sampler.peak - sampler.baseline) >> 20} MB peak, "
        f"+{(final - sampler.baseline) >> 20} MB at the end"
    )
    print(report)  # the figures, with -s
    for text, (_, expected) in zip(texts, PROGRAMS, strict=True):
        assert expected in text, report
    assert ten_mb and closed >= 500 - 32, report
    assert reader.error is None and reader.missed() == 0 and len(reader.stamps) > 1000, report
    assert reader.longest < 2.0 and pinger.error is None and pinger.longest < 2.0, report
    assert sampler.peak - sampler.baseline < MEMORY_BUDGET + (96 << 20), report
    assert final - sampler.baseline < 96 << 20, report
