"""Who reads the socket: the caller while it iterates, the reader thread when it stops.

On real loopback sockets against the emulator at 500 Hz: records come in order with
no gap either way, and the connection is drained while nobody asks for records.
"""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Iterator
from typing import Any

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.rtde import client as client_module


@pytest.fixture
def emu() -> Iterator[EmulatorThread]:
    running = EmulatorThread(
        EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0, realtime_port=None, dashboard_port=None)
    ).start()
    yield running
    running.stop()


def steps(stamps: list[float]) -> list[int]:
    return [round((b - a) * 500) for a, b in itertools.pairwise(stamps)]


def test_the_caller_reads_while_it_iterates_and_the_reader_drains_when_it_stops(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        client.setup_outputs(["timestamp", "actual_q"], 500)
        readers: list[str] = []  # the thread of every read, in order
        one_record, receive = client.core.one_record, client.core.receive

        def one(data: bytes) -> Any:  # the caller's reads all come here first
            readers.append(threading.current_thread().name)
            return one_record(data)

        def events(data: bytes) -> Any:  # the reader thread's reads (and the caller's longer ones)
            if threading.current_thread() is not threading.main_thread():
                readers.append(threading.current_thread().name)
            return receive(data)

        client.core.one_record = one  # type: ignore[method-assign]
        client.core.receive = events  # type: ignore[method-assign]
        client.start()
        stamps, later = [], 0
        for record in client:
            stamps.append(record.timestamp)
            if len(stamps) == 50:
                later = len(readers)
            if len(stamps) == 300:
                break
        assert steps(stamps) == [1] * 299  # in order, none lost
        # once the caller iterates, its own thread does every read
        assert readers[later:] and set(readers[later:]) == {threading.main_thread().name}
        # nobody asks for LEASE and more: the reader thread drains into the queue
        before = client.received
        time.sleep(client_module.LEASE + 0.5)
        assert client.received - before >= 100
        assert client.connection_lost is None
        more = [client.receive().timestamp for _ in range(50)]
        assert steps([stamps[-1], *more]) == [1] * 50  # the queue went on where the caller stopped


def test_a_request_while_iterating_gets_its_reply_at_once(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        client.setup_outputs(["timestamp"], 500)
        client.start()
        for _, _record in zip(range(100), client, strict=False):
            pass
        began = time.monotonic()
        client.pause()  # the caller stopped reading: its reply must not wait for the lease to end
        assert time.monotonic() - began < 5
        with pytest.raises(TimeoutError):  # paused: what came before the reply, then nothing
            for _ in range(1000):
                client.receive(timeout=0.3)
        client.start()
        assert client.receive().timestamp > 0  # and the caller reads again after a request


def test_timeouts_shorter_and_longer_than_a_read_slice_are_kept(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        client.setup_outputs(["timestamp"], 500)  # not started: nothing comes
        for wait in (client_module.SLICE / 2, client_module.SLICE * 3.5):
            began = time.monotonic()
            with pytest.raises(TimeoutError, match="no data package"):
                client.receive(timeout=wait)
            assert wait * 0.9 <= time.monotonic() - began < wait + 2
        client.start()
        assert client.receive(timeout=client_module.SLICE / 2 + 2).timestamp > 0
