"""Who reads the socket: the caller while it iterates, the reader thread when it stops.

On real loopback sockets against the emulator at 500 Hz: records come in order with
no gap either way, and the connection is drained while nobody asks for records.
"""

from __future__ import annotations

import itertools
import threading
import time
from typing import Any

import pytest

from rtde_spec import EmulatorThread, RtdeClient
from rtde_spec.rtde import client as client_module


@pytest.fixture
def emu(rtde_emulator: EmulatorThread) -> EmulatorThread:
    return rtde_emulator


def steps(stamps: list[float]) -> list[int]:
    return [round((b - a) * 500) for a, b in itertools.pairwise(stamps)]


def test_the_caller_reads_while_it_iterates_and_the_reader_drains_when_it_stops(emu: EmulatorThread) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        readers: list[str] = []  # the thread of every read that took the general path
        receive = client.core.receive

        def events(data: bytes) -> Any:  # every read the reader thread makes comes here
            readers.append(threading.current_thread().name)
            return receive(data)

        client.core.receive = events  # type: ignore[method-assign]
        client.setup_outputs(["timestamp", "actual_q"], 500)
        size = client.core.output.package_size  # type: ignore[union-attr]
        client.start()
        stamps, later = [], 0
        for record in client:
            stamps.append(record.timestamp)
            if len(stamps) == 50:
                later = len(readers)
            if len(stamps) == 300:
                break
        assert steps(stamps) == [1] * 299  # in order, none lost
        # once the caller iterates, its own thread does every read, one package each, with no events
        assert set(readers[later:]) <= {threading.main_thread().name}
        assert len(readers[later:]) < 50  # of 250 reads: most were one package each (a slow read holds more)
        assert client.core.framer.offset + client.core.taken >= 300 * size  # the stream's offsets still count
        # nobody asks for LEASE and more: the reader thread drains into the queue
        before, made = client.received, len(readers)
        time.sleep(client_module.LEASE + 0.5)
        assert client.received - before >= 100
        assert readers[made:] and threading.main_thread().name not in readers[made:]
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


def test_a_caller_that_falls_behind_gets_the_packages_it_missed_in_order(emu: EmulatorThread) -> None:
    """A slow loop body (shorter than the lease) lets packages pile up in the socket: the next
    read holds many, which leave the one-package path and come in order through the queue."""
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        client.setup_outputs(["timestamp", "actual_q"], 500)
        client.start()
        stamps: list[float] = []
        for record in client:
            stamps.append(record.timestamp)
            if len(stamps) in (20, 60, 100):
                time.sleep(client_module.LEASE / 4)  # ~25 packages arrive meanwhile
            if len(stamps) == 200:
                break
        assert steps(stamps) == [1] * 199
        assert client.skipped == 0


def test_a_batched_client_iterates_in_order_and_each_of_two_callbacks_gets_every_record(
    emu: EmulatorThread,
) -> None:
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5, batch=20) as client:
        client.setup_outputs(["timestamp"], 500)
        client.start()
        iterated = [record.timestamp for _, record in zip(range(100), client, strict=False)]
        assert steps(iterated) == [1] * 99
    first: list[Any] = []
    second: list[float] = []
    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5, batch=20) as client:
        client.setup_outputs(["timestamp"], 500)
        client.on_data(first.append)
        client.on_data(lambda record: second.append(record.timestamp))
        client.start()
        deadline = time.monotonic() + 5
        while len(second) < 100 and time.monotonic() < deadline:
            time.sleep(0.01)
        client.pause()
    assert len(second) >= 100 and steps(second) == [1] * (len(second) - 1)
    assert [r.timestamp for r in first[: len(second)]] == second[: len(first)]


def test_an_error_raised_by_a_callback_ends_the_connection_with_that_error(emu: EmulatorThread) -> None:
    def fails(record: Any) -> None:
        raise ValueError(f"the user's callback refused {record.timestamp}")

    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        client.setup_outputs(["timestamp"], 500)
        client.on_data(fails)
        client.start()
        deadline = time.monotonic() + 5
        while client.connection_lost is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert isinstance(client.connection_lost, ValueError)
        assert "refused" in str(client.connection_lost)


def test_packages_taken_one_per_read_still_count_in_the_offsets_of_a_later_fault() -> None:
    """The caller's one-package reads bypass the framer; the stream offset of a later framing
    fault still counts their bytes (a size below the header, 36 bytes after the replies)."""
    from rtde_spec.errors import DecodeError
    from tests.faults.clients_peer import HostilePeer

    peer = HostilePeer()
    got: list[float] = []
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        client.setup_outputs(["timestamp"], 125)
        client.start()
        start = client.core.framer.offset  # the replies before the data
        records = iter(client)
        for stamp in (1.0, 2.0, 3.0):
            peer.send(peer.data(stamp))  # one package per read
            got.append(next(records).timestamp)
        # the first read may be the reader thread's (it was waiting when the caller came)
        assert client.core.taken >= 24 and client.core.framer.offset + client.core.taken == start + 36
        peer.send(b"\x00\x01\x78")  # a size below the header
        with pytest.raises(DecodeError) as caught:
            next(records)
    peer.close()
    assert got == [1.0, 2.0, 3.0]
    assert caught.value.offset == start + 3 * 12


def test_reading_before_connect_is_a_usage_error_at_once() -> None:
    """A client never connected had no socket: iterating or receive() failed an assertion, and
    the asyncio client waited its whole time-out before a TimeoutError."""
    import asyncio

    from rtde_spec.errors import UsageError
    from rtde_spec.rtde.aio import AsyncRtdeClient

    client = RtdeClient("127.0.0.1", 1, timeout=5.0)  # nothing is sent: no connection is made
    start = time.monotonic()
    with pytest.raises(UsageError, match="not connected: call connect"):
        client.receive()
    with pytest.raises(UsageError, match="not connected"):
        list(client)

    async def receive() -> None:
        await AsyncRtdeClient("127.0.0.1", 1, timeout=5.0).receive()

    with pytest.raises(UsageError, match="not connected"):
        asyncio.run(receive())
    assert time.monotonic() - start < 2.0


def test_a_time_out_of_zero_does_not_wait_and_errors_name_the_time_out_given(emu: EmulatorThread) -> None:
    """`receive(timeout=0)` waited the client's whole time-out (0 was read as "not given"), and a
    time-out longer than a read slice was named less one slice ("within 4.9 s" for 5)."""
    import asyncio

    from rtde_spec.rtde.aio import AsyncRtdeClient

    with RtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
        client.setup_outputs(["timestamp"], 500)  # not started: nothing comes
        for wait, named in ((0, "within 0 s"), (None, "within 5 s"), (0.5, "within 0.5 s")):
            began = time.monotonic()
            with pytest.raises(TimeoutError, match=named):
                client.receive(timeout=wait) if wait is not None else client.receive()
            assert time.monotonic() - began < (wait if wait is not None else 5) + 1

    async def asynchronous() -> float:
        async with AsyncRtdeClient("127.0.0.1", emu.ports["rtde"], timeout=5) as client:
            await client.setup_outputs(["timestamp"], 500)
            began = time.monotonic()
            with pytest.raises(TimeoutError):
                await client.receive(timeout=0)
            return time.monotonic() - began

    assert asyncio.run(asynchronous()) < 1
