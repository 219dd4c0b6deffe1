"""`RtdeClient.on_batch`: every data package, in order, as numpy arrays, one per read of the socket.

On real loopback sockets against the emulator at 500 Hz: the arrays hold exactly the packages
the raw callbacks see, no record is made unless an `on_data` callback wants them, and the
recorder (which takes its rows this way) writes every row once.
"""

from __future__ import annotations

import asyncio
import itertools
import time
from typing import Any

import pytest

from rtde_spec import EmulatorThread, RtdeClient
from rtde_spec.errors import UsageError
from tests.test_client_reads import steps

np = pytest.importorskip("numpy")


def wait_for(count: Any, wanted: int) -> None:
    deadline = time.monotonic() + 5
    while count() < wanted and time.monotonic() < deadline:
        time.sleep(0.01)


@pytest.mark.parametrize("batch", [1, 20])
def test_arrays_hold_every_package_in_order_as_the_raw_callbacks_see_them(
    rtde_emulator: EmulatorThread, batch: int
) -> None:
    arrays: list[Any] = []
    raws: list[bytes] = []
    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], batch=batch) as client:
        client.setup_outputs(["timestamp", "actual_q", "robot_mode"], 500)
        client.on_batch(arrays.append)
        client.on_raw(raws.append)
        assert client.core.want_records is False  # no record made for anyone
        client.start()
        wait_for(lambda: sum(map(len, arrays)), 200)
        with pytest.raises(UsageError, match="on_batch"):
            client.receive()
        client.pause()
        codec = client.core.output
        assert codec is not None
    assert all(a.dtype == codec.dtype and not a.flags.writeable for a in arrays)  # views of the reads
    assert b"".join(a.tobytes() for a in arrays) == b"".join(raws)  # the very packages, byte for byte
    rows = np.concatenate(arrays)
    assert len(rows) == len(raws) == client.received >= 200 and client.skipped == 0
    assert steps(rows["timestamp"].tolist()) == [1] * (len(rows) - 1)
    last = codec.decode_package(raws[-1])
    assert rows["actual_q"][-1].tolist() == list(last.actual_q) and rows["robot_mode"][-1] == last.robot_mode
    sizes = [len(a) for a in arrays]
    if batch == 1:
        assert sorted(sizes)[len(sizes) // 2] == 1  # a read a package, more when the reader was late
    else:
        assert sorted(sizes)[len(sizes) // 2] >= batch  # a read per batch: one array per batch


def test_arrays_and_records_both_get_every_package(rtde_emulator: EmulatorThread) -> None:
    """With an `on_data` callback too, the reader's shortest path hands out both."""
    arrays: list[Any] = []
    records: list[Any] = []
    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], batch=20) as client:
        client.setup_outputs(["timestamp", "actual_q"], 500)
        client.on_data(records.append)
        client.on_batch(arrays.append)
        assert client.core.want_records is True
        client.start()
        wait_for(lambda: len(records), 150)
        client.pause()
    stamps = np.concatenate(arrays)["timestamp"].tolist()
    assert stamps == [r.timestamp for r in records] and len(stamps) >= 150


def test_a_callback_added_after_start_gets_the_packages_from_then_on(rtde_emulator: EmulatorThread) -> None:
    raws: list[bytes] = []
    arrays: list[Any] = []
    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], batch=10) as client:
        client.setup_outputs(["timestamp"], 500)
        client.on_raw(raws.append)
        client.start()
        wait_for(lambda: len(raws), 50)
        client.on_batch(arrays.append)
        wait_for(lambda: sum(map(len, arrays)), 50)
        client.pause()
    stamps = np.concatenate(arrays)["timestamp"].tolist()
    assert len(stamps) >= 50 and steps(stamps) == [1] * (len(stamps) - 1)
    codec = client.core.output
    assert codec is not None
    assert stamps == [codec.decode_package(r).timestamp for r in raws[len(raws) - len(stamps) :]]


def test_an_error_raised_by_a_batch_callback_ends_the_connection_with_that_error(
    rtde_emulator: EmulatorThread,
) -> None:
    def fails(array: Any) -> None:
        raise ValueError(f"the user's callback refused {len(array)} rows")

    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], timeout=5, batch=5) as client:
        client.setup_outputs(["timestamp"], 500)
        client.on_batch(fails)
        client.start()
        wait_for(lambda: client.connection_lost is not None, 1)
        assert isinstance(client.connection_lost, ValueError) and "refused" in str(client.connection_lost)


def test_recording_writes_every_row_once_up_to_the_sample_count(
    rtde_emulator: EmulatorThread, tmp_path: Any
) -> None:
    """The recorder takes arrays: a sample count met inside a read keeps only the rows owed,
    and a vector's elements land in columns of their own."""
    pq = pytest.importorskip("pyarrow.parquet")
    from rtde_spec.output.writers import open_writer
    from rtde_spec.rtde.recorder import record

    writer = open_writer("parquet", tmp_path / "rows.parquet")
    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], batch=40) as client:
        result = record(client, ["timestamp", "actual_q"], 500, writer, samples=333)
    writer.close()
    table = pq.read_table(tmp_path / "rows.parquet")
    stamps = table.column("timestamp").to_pylist()
    assert result.rows == table.num_rows == 333 and result.skipped == 0
    # in order, none twice (an EmulatorThread may skip a step while the test process is busy)
    assert all(b > a for a, b in itertools.pairwise(stamps))
    assert [c for c in table.column_names if c.startswith("actual_q")] == [f"actual_q_{i}" for i in range(6)]


def test_packages_split_across_reads_and_mixed_with_texts_reach_the_arrays_whole_and_in_order() -> None:
    """A real network cuts packages anywhere: the framer holds the parts; the arrays hold whole
    packages in order, and a framing fault ends the connection after the packages before it."""
    from rtde_spec.rtde.codec import build
    from tests.faults.clients_peer import HostilePeer

    peer = HostilePeer()
    arrays: list[Any] = []
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        client.setup_outputs(["timestamp"], 125)
        client.on_batch(arrays.append)
        client.start()
        text = build("text_message", message="between the packages", source="test", warning_level=1)
        stream = b"".join(peer.data(float(n)) for n in range(20)) + text
        stream += b"".join(peer.data(float(n)) for n in range(20, 40))
        for at in range(0, len(stream), 7):  # 7-byte pieces: every package cut, some twice
            peer.send(stream[at : at + 7])
            time.sleep(0.001)
        wait_for(lambda: sum(map(len, arrays)), 40)
        peer.send(b"\x00\x01\x78")  # a size below the header: the connection ends with its error
        wait_for(lambda: client.connection_lost is not None, 1)
    peer.close()
    assert np.concatenate(arrays)["timestamp"].tolist() == [float(n) for n in range(40)]
    assert client.connection_lost is not None and "size" in str(client.connection_lost)


async def _async_arrays(port: int, batch: int) -> tuple[list[Any], Any]:
    from rtde_spec.rtde.aio import AsyncRtdeClient

    arrays: list[Any] = []
    async with AsyncRtdeClient("127.0.0.1", port, batch=batch) as client:
        await client.setup_outputs(["timestamp", "actual_q"], 500)
        client.on_batch(arrays.append)
        await client.start()
        deadline = time.monotonic() + 5
        while sum(map(len, arrays)) < 150 and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
        with pytest.raises(UsageError, match="on_batch"):
            await client.receive()
        await client.pause()  # answered while arrays come: the reply is not held back
        assert client.received == sum(map(len, arrays)) and not client._data  # no record queued
        return arrays, client.core.output


@pytest.mark.parametrize("batch", [1, 20])
def test_the_asyncio_client_hands_over_arrays_too(rtde_emulator: EmulatorThread, batch: int) -> None:
    arrays, codec = asyncio.run(_async_arrays(rtde_emulator.ports["rtde"], batch))
    assert all(a.dtype == codec.dtype and not a.flags.writeable for a in arrays)
    stamps = np.concatenate(arrays)["timestamp"].tolist()
    assert len(stamps) >= 150 and steps(stamps) == [1] * (len(stamps) - 1)
    if batch > 1:
        assert sorted(map(len, arrays))[len(arrays) // 2] >= batch


def test_protocol_1_packages_without_their_recipe_id_come_as_rows_of_the_recipe() -> None:
    """A CB3-era controller (protocol 1) may send data packages without the id byte: each is read
    with the implied id, so the arrays have the recipe's dtype like any other."""
    import struct

    from rtde_spec._generated.rtde_models import DataPackage
    from tests.faults.clients_peer import HEADER, HostilePeer

    peer = HostilePeer(accept_versions=(1,))  # its recipes are DOUBLE fields only
    arrays: list[Any] = []
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        client.setup_outputs(["timestamp"], 125)
        client.on_batch(arrays.append)
        client.start()
        codec = client.core.output
        assert codec is not None and client.core.state.version == 1
        data = DataPackage.PACKAGE_TYPE
        bare = [HEADER.pack(HEADER.size + 8, data) + struct.pack(">d", n) for n in range(10)]  # no id
        peer.send(b"".join(bare[n] if n % 2 else peer.data(float(n)) for n in range(10)))  # both forms
        wait_for(lambda: sum(map(len, arrays)), 10)
        assert client.connection_lost is None
    peer.close()
    rows = np.concatenate(arrays)
    assert all(a.dtype == codec.dtype for a in arrays)
    assert len(arrays) < 10  # one array per read, not one per package of either form
    assert rows["timestamp"].tolist() == [float(n) for n in range(10)] and set(rows["recipe_id"]) == {1}


@pytest.mark.parametrize("batch", [1, 20])
def test_the_callbacks_of_a_read_run_raw_then_batch_then_records(
    rtde_emulator: EmulatorThread, batch: int
) -> None:
    """`record --wall-clock` notes each read's time before the recorder takes its rows: the order
    of a read's callbacks is part of the API (it was batch, raw, records for a day: host times
    could shift by a read when the recorder flushed between the two)."""
    raws: list[bytes] = []
    records: list[Any] = []
    rows: list[int] = []
    wrong: list[tuple[int, int, int]] = []

    def batch_seen(array: Any) -> None:
        rows.append(len(array))
        if len(raws) != sum(rows) or len(records) != sum(rows) - len(array):
            wrong.append((len(raws), sum(rows), len(records)))

    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], batch=batch) as client:
        client.setup_outputs(["timestamp"], 500)
        client.on_data(records.append)
        client.on_batch(batch_seen)
        client.on_raw(raws.append)  # added last, called first
        client.start()
        wait_for(lambda: sum(rows), 150)
        client.pause()
    assert sum(rows) >= 150 and not wrong, wrong[:5]


def test_reads_of_whole_packages_skip_the_general_path_with_only_batch_callbacks(
    rtde_emulator: EmulatorThread,
) -> None:
    """A batch-only client frames a read of whole packages on the reader's shortest path: no
    events, no runs, no list of package bytes (what a recorder at 500 Hz does 10 times a second)."""
    arrays: list[Any] = []
    general: list[int] = []
    with RtdeClient("127.0.0.1", rtde_emulator.ports["rtde"], batch=20) as client:
        receive = client.core.receive

        def events(data: bytes) -> Any:  # every read that takes the general path comes here
            general.append(len(data))
            return receive(data)

        client.core.receive = events  # type: ignore[method-assign]
        client.setup_outputs(["timestamp", "actual_q"], 500)
        client.on_batch(arrays.append)
        client.start()
        wait_for(lambda: len(arrays), 3)
        before = len(general)
        wait_for(lambda: sum(map(len, arrays)), 300)
        during = len(general) - before
        client.pause()
    assert sum(map(len, arrays)) >= 300 and during <= 1, general[before:]
