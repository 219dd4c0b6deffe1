"""When the emulator reads a client's inputs: as a controller does, at the start of the cycle whose
state it sends at the cycle's end (server/loop.py computes a step just before it is due).

ur_rtde asks its control script for the arm model's answers (`getJacobian`, `getMassMatrix`, ...)
by writing a command into an input register and reading the output registers of the first
package that comes after. The emulator used to compute each step right after sending the one
before, so an input that came after a package was read two packages later and ur_rtde's first
answer was the previous call's. Here a client does what ur_rtde does, with this library's own
RTDE client: it takes a package as it comes, writes an input, and reads the next package once.
The emulator runs in its own process (`rtde-spec serve` on free ports), as against a robot.
"""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest

from rtde_spec import RtdeClient

ROUNDS = 20  # inputs that left in time, to count
MOST_ROUNDS = 100  # tries, to find them on a loaded machine
STEP = 0.002  # s, 500 Hz
IN_TIME = 0.0003  # s from a package to the input sent after it: well inside the step's first 40 %
ECHO = (
    b"def echo():\n  while True:\n"
    b"    write_output_integer_register(24, read_input_integer_register(24))\n    sync()\n  end\nend\n"
)


@pytest.fixture
def ports() -> Iterator[dict[str, int]]:
    """The ports of an emulator of this tree in its own process."""
    ports = ["--rtde-port", "0", "--primary-port", "0", "--secondary-port", "0"]
    off = ["--realtime-port", "-1", "--dashboard-port", "-1"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "serve", "--host", "127.0.0.1", *ports, *off],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        yield {name: int(port) for name, port in re.findall(r"(\w+) (\d+)", line.split(":", 1)[-1])}
    finally:
        proc.terminate()
        proc.wait(10)


def test_an_input_written_after_a_package_is_answered_in_the_next_package(ports: dict[str, int]) -> None:
    with RtdeClient("127.0.0.1", ports["rtde"]) as client:
        client.setup_outputs(["timestamp", "output_int_register_24"], 500)
        inputs = client.setup_inputs(["input_int_register_24"])
        client.start()
        with socket.create_connection(("127.0.0.1", ports["primary"]), timeout=5) as primary:
            primary.sendall(ECHO)
            time.sleep(0.2)
        client.receive(timeout=2)
        while True:  # the packages that came while the program started
            try:
                client.receive(timeout=1e-4)
            except TimeoutError:
                break
        rounds = []  # (package time, when the input had left by this process's clock, answered, skipped)
        for value in range(1, MOST_ROUNDS + 1):
            first = client.receive(timeout=2)  # a package as it comes (the client waited for it)
            client.send(inputs, input_int_register_24=value)
            sent = time.perf_counter()
            following = client.receive(timeout=2)
            skipped = following.timestamp - first.timestamp > 1.5 * STEP  # the emulator skipped a step
            rounds.append((first.timestamp, sent, following.output_int_register_24 == value, skipped))
    # the package's time and this clock differ by the delivery and a constant: the least difference
    # is a package taken at once, and an input sent more than IN_TIME after its package's time was
    # held up here (this process waited for a core), too late for any controller's next cycle
    base = min(sent - stamp for stamp, sent, _, _ in rounds)
    answered = [ok for stamp, sent, ok, skipped in rounds if sent - stamp - base < IN_TIME and not skipped]
    assert len(answered) >= ROUNDS, f"only {len(answered)} of {len(rounds)} inputs left in time"
    # an input that a loaded machine delays past the start of the next step's computation is in
    # the package after (as on a controller); the old emulator answered none in the next package
    assert sum(answered) >= len(answered) * 3 // 4, answered
