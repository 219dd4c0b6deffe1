"""A controller's stream cut anywhere reaches every kind of callback whole, in order, once.

A real network hands a client its bytes in pieces that end anywhere: inside a header, between
a text message and a data package, several packages at once. Whatever the cuts, the raw, batch
(numpy) and record callbacks of a blocking client each see every data package once, in the
order sent, in the order raw, batch, records within each read; `received` counts each once.
Real TCP on loopback against a scripted controller (tests/faults/clients_peer.py).
"""

from __future__ import annotations

import time
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtde_spec import RtdeClient
from rtde_spec.rtde.codec import build
from tests.budget import examples
from tests.faults.clients_peer import HostilePeer

np = pytest.importorskip("numpy")

TEXT = build("text_message", message="between the packages", source="test", warning_level=1)


def stream(count: int, texts: set[int], peer: HostilePeer) -> bytes:
    """`count` one-DOUBLE data packages (their value: their number), a text message before each
    number in `texts`."""
    return b"".join((TEXT if n in texts else b"") + peer.data(float(n)) for n in range(count))


@settings(max_examples=examples(40), deadline=None)
@given(
    count=st.integers(1, 60),
    texts=st.sets(st.integers(0, 59), max_size=6),
    cuts=st.lists(st.integers(1, 200), min_size=1, max_size=40),
    batch=st.sampled_from([1, 4]),
    kinds=st.sets(st.sampled_from(["raw", "batch", "records"]), min_size=1),
)
def test_every_callback_sees_every_package_once_in_order_whatever_the_cuts(
    count: int, texts: set[int], cuts: list[int], batch: int, kinds: set[str]
) -> None:
    peer = HostilePeer()
    seen: dict[str, list[float]] = {"raw": [], "batch": [], "records": []}
    order: list[tuple[str, int]] = []  # each call's kind and packages, for the order within a read
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0, batch=batch) as client:
        client.setup_outputs(["timestamp"], 125)
        codec = client.core.output
        assert codec is not None

        def raw(package: bytes) -> None:
            order.append(("raw", 1))
            seen["raw"].append(codec.decode_package(package).timestamp)

        def arrays(array: Any) -> None:
            order.append(("batch", len(array)))
            seen["batch"].extend(array["timestamp"].tolist())

        def records(record: Any) -> None:
            order.append(("records", 1))
            seen["records"].append(record.timestamp)

        for kind, add, callback in (
            ("records", client.on_data, records),
            ("batch", client.on_batch, arrays),
            ("raw", client.on_raw, raw),
        ):
            if kind in kinds:
                add(callback)  # type: ignore[operator]
        client.start()
        data, at, i = stream(count, texts, peer), 0, 0
        while at < len(data):  # the cuts, again and again, until the stream is sent
            piece = cuts[i % len(cuts)]
            peer.send(data[at : at + piece])
            at, i = at + piece, i + 1
            time.sleep(0.0005)  # most pieces a read of their own
        deadline = time.monotonic() + 5
        while client.received < count and time.monotonic() < deadline:
            time.sleep(0.005)
        lost = client.connection_lost
    peer.close()
    assert lost is None, lost
    want = [float(n) for n in range(count)]
    for kind in kinds:
        assert seen[kind] == want, (kind, seen[kind][:10])
    assert client.received == count
    done = {"raw": 0, "batch": 0, "records": 0}  # packages each kind has seen so far
    for kind, packages in order:  # a read's raws come before its array, its array before its records
        done[kind] += packages
        if kind == "batch" and "raw" in kinds:
            assert done["raw"] == done["batch"], order[:20]
        if kind == "batch" and "records" in kinds:
            assert done["records"] == done["batch"] - packages, order[:20]
        if kind == "records" and "batch" in kinds:
            assert done["records"] <= done["batch"], order[:20]
