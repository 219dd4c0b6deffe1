"""The control loop's clock: never wakes before a step's due time, on Linux without spinning.

How late it wakes is the benchmark's business (`bench_emulator.py --control-script`); these
tests hold what must always be true: not early, the timerfd in use where Linux has it, the
fallback equally correct, and a real-time priority the system refuses costs nothing but a line.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import sys
import time

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.emulator.controller.clock import StepClock


async def _wakes(precise: bool, count: int = 40) -> list[float]:
    clock = StepClock()
    try:
        assert clock.precise is sys.platform.startswith("linux")
        if not precise:
            clock.close()  # the sleep-and-spin way every platform has
        early = []
        start = time.perf_counter()
        for step in range(1, count + 1):
            due = start + step * 0.002
            await clock.until(due)
            early.append(due - time.perf_counter())
        await clock.until(time.perf_counter() - 1.0)  # a due time already past returns at once
        return early
    finally:
        clock.close()


@pytest.mark.parametrize("precise", [True, False])
def test_the_clock_never_wakes_before_the_due_time(precise: bool) -> None:
    early = asyncio.run(_wakes(precise))
    assert len(early) == 40 and max(early) <= 0.0


def test_a_real_time_priority_the_system_refuses_is_one_log_line_and_the_emulator_serves(
    caplog: pytest.LogCaptureFixture,
) -> None:
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=None,
        secondary_port=None,
        realtime_priority=1000,
        realtime_port=None,
        dashboard_port=None,
        skip_after=None,
    )
    with caplog.at_level(logging.WARNING, "rtde_spec.emulator"), EmulatorThread(config) as emu:
        with RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
            client.setup_outputs(["timestamp"], 500)
            client.start()
            stamps = [client.receive().timestamp for _ in range(20)]
    assert [round((b - a) * 500) for a, b in itertools.pairwise(stamps)] == [1] * 19
    refused = [r.getMessage() for r in caplog.records if "SCHED_FIFO" in r.getMessage()]
    assert len(refused) == 1 and "normal priority" in refused[0]


def test_serve_takes_a_real_time_priority_and_refuses_one_out_of_range() -> None:
    import subprocess

    ports = ["--rtde-port", "0", "--primary-port", "0", "--secondary-port", "0"]
    ports += ["--realtime-port", "-1", "--dashboard-port", "-1"]
    bad = subprocess.run(
        [sys.executable, "-m", "rtde_spec", "serve", *ports, "--realtime-priority", "100"],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    assert bad.returncode == 2 and "--realtime-priority 100: give 1..99" in bad.stderr
    with subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "serve", *ports, "--realtime-priority", "5"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    ) as serve:  # fmt: skip
        try:
            assert serve.stdout is not None
            line = serve.stdout.readline()
            assert line.startswith("emulating controller") and "rtde" in line, line
        finally:
            serve.terminate()
            serve.wait(30)
