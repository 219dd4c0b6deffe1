"""Slow end-to-end tests (`@pytest.mark.slow`) are left out of a plain `pytest`, so the
contributor's loop stays short; CI runs them (`.ci/run` sets RTDE_SPEC_SLOW=1), and so does
`RTDE_SPEC_SLOW=1 python3 -m pytest` or any `-m` expression that selects them (`-m slow`)."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

from . import durations
from .fixed_ports import fixed_ports
from .spinning_threads import WATCH


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    order = durations.longest_first([item.nodeid for item in items], durations.load())
    items[:] = [items[i] for i in order]  # every process sorts alike: xdist checks they agree
    if os.environ.get("RTDE_SPEC_SLOW") == "1" or config.getoption("markexpr"):
        return
    slow = [item for item in items if item.get_closest_marker("slow") is not None]
    if slow:
        items[:] = [item for item in items if item.get_closest_marker("slow") is None]
        config.hook.pytest_deselected(items=slow)


def pytest_report_header(config: pytest.Config) -> str:
    if os.environ.get("RTDE_SPEC_SLOW") == "1" or config.getoption("markexpr"):
        return "slow tests: included"
    return "slow tests: left out (RTDE_SPEC_SLOW=1 or -m slow runs them; CI does)"


@pytest.fixture(scope="module", autouse=True)
def _fixed_ports(request: pytest.FixtureRequest) -> Iterator[None]:
    """A module marked `fixed_ports(HOST, ...)` holds those addresses' controller ports for its run
    (tests/fixed_ports.py): it waits for any other run on the machine that holds them."""
    marker = request.node.get_closest_marker("fixed_ports")
    if marker is None:
        yield
        return
    with fixed_ports(*marker.args):
        yield


@pytest.fixture(scope="module", autouse=True)
def _no_thread_left_spinning(request: pytest.FixtureRequest) -> Iterator[None]:
    """A thread an earlier module left running that keeps a core busy fails here, named
    (tests/spinning_threads.py): it would slow every later test of this process."""
    yield
    spinning = WATCH.spinning_after(request.module.__name__)
    assert not spinning, "; ".join(spinning)


@pytest.fixture(scope="session", autouse=True)
def _no_thread_left_spinning_by_the_last_module() -> Iterator[None]:
    """The same for the last module a process runs: no module comes after it to look."""
    yield
    spinning = WATCH.spinning_at_the_end()
    assert not spinning, "; ".join(spinning)


@pytest.fixture
def rtde_emulator() -> Iterator[object]:
    """An `EmulatorThread` of the test's own, RTDE and primary on free ports, nothing else."""
    from rtde_spec import EmulatorConfig, EmulatorThread

    running = EmulatorThread(
        EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0, realtime_port=None, dashboard_port=None)
    ).start()
    yield running
    running.stop()
