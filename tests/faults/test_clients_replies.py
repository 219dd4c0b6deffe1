"""Clients against a misbehaving controller: replies matched to requests by type, and a protocol
error ends iteration with that error in the blocking and the asyncio client alike.

A real socket on 127.0.0.1 (tests/faults/clients_peer.py) plays the controller.
"""

from __future__ import annotations

import asyncio
import logging
import re
from typing import Any

import pytest

from rtde_spec import AsyncRtdeClient, RtdeClient
from rtde_spec.errors import DecodeError, ProtocolError
from rtde_spec.rtde.codec import build
from tests.faults.clients_peer import HostilePeer


def wrong_setup_reply(kind: int, package: bytes, peer: HostilePeer) -> bytes:
    """The first setup request gets a start reply; everything after is answered right."""
    if chr(kind) == "O" and peer.requests.count("O") == 1:
        return build("start_reply", accepted=True)
    return peer.normal(kind, package)


def test_a_reply_of_the_wrong_type_is_an_error_naming_both_and_later_replies_are_right() -> None:
    peer = HostilePeer(wrong_setup_reply)
    with RtdeClient("127.0.0.1", peer.port, timeout=1.0) as client:
        with pytest.raises(ProtocolError, match=r"requested setup_outputs_v2, got start_reply") as info:
            client.setup_outputs(["timestamp"], 125)
        assert info.value.expected == "setup_outputs_v2_reply" and info.value.actual == "start_reply"
        codec = client.setup_outputs(["timestamp"], 125)  # answered right this time
        assert codec is not None and codec.names == ("timestamp",)
        client.start()
        peer.send(peer.data(1.5) + peer.data(2.5))
        assert [client.receive().timestamp for _ in range(2)] == [1.5, 2.5]
    peer.close()


def test_the_asyncio_client_names_a_wrong_reply_too_and_goes_on() -> None:
    peer = HostilePeer(wrong_setup_reply)

    async def run() -> list[float]:
        async with AsyncRtdeClient("127.0.0.1", peer.port, timeout=1.0) as client:
            with pytest.raises(ProtocolError, match=r"requested setup_outputs_v2, got start_reply"):
                await client.setup_outputs(["timestamp"], 125)
            await client.setup_outputs(["timestamp"], 125)
            await client.start()
            peer.send(peer.data(1.5) + peer.data(2.5))
            return [(await client.receive()).timestamp for _ in range(2)]

    assert asyncio.run(run()) == [1.5, 2.5]
    peer.close()


def extra_replies(kind: int, package: bytes, peer: HostilePeer) -> bytes:
    """Every request answered right, and with replies nobody asked for in the same segment."""
    normal = peer.normal(kind, package)
    letter = chr(kind)
    if letter == "V":
        return normal + normal  # a second protocol-version reply
    if letter == "v":  # a setup reply nobody asked for
        return normal + build("setup_outputs_v2_reply", output_recipe_id=7, variable_types=["INT32"])
    if letter == "S":
        return (
            normal
            + build("start_reply", accepted=False)
            + build("get_urcontrol_version_reply", major=9, minor=9, bugfix=9, build=9)
        )
    return normal


def test_unsolicited_replies_are_logged_and_never_shift_later_replies(caplog: Any) -> None:
    caplog.set_level(logging.WARNING, logger="rtde_spec.client")
    peer = HostilePeer(extra_replies)
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        assert client.protocol_version == 2 and str(client.controller_version) == "5.15.0"
        codec = client.setup_outputs(["timestamp"], 125)
        assert codec is not None and client.core.output_recipe_id == 1
        client.start()
        assert str(client.controller_version) == "5.15.0"  # the stray version reply changed nothing
        peer.send(peer.data(1.0))
        assert client.receive().timestamp == 1.0
        # mid-stream, a setup reply no one asked for: the recipe stays, the next request gets its own
        peer.send(build("setup_outputs_v2_reply", output_recipe_id=7, variable_types=["INT32"]))
        peer.send(peer.data(2.0))
        assert client.receive().timestamp == 2.0
        client.pause()
        assert client.core.output_recipe_id == 1 and client.core.unsolicited == 5
        assert client.connection_lost is None
    assert sum("nobody asked for" in r.getMessage() for r in caplog.records) == 5
    peer.close()


def test_the_asyncio_client_ignores_unsolicited_replies_too() -> None:
    peer = HostilePeer(extra_replies)

    async def run() -> tuple[str, float, int]:
        async with AsyncRtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
            await client.setup_outputs(["timestamp"], 125)
            await client.start()
            peer.send(peer.data(3.0))
            record = await client.receive()
            await client.pause()
            return str(client.controller_version), record.timestamp, client.core.output_recipe_id or 0

    assert asyncio.run(run()) == ("5.15.0", 3.0, 1)
    peer.close()


BAD_PACKAGES = {  # the bytes, the error, what its message says
    "data of a recipe never set up": (
        build("data_package", recipe_id=9, payload=b"\0" * 8),
        ProtocolError,
        "no recipe this client set up (expected 1, got 9)",
    ),
    "data of the recipe cut short": (
        build("data_package", recipe_id=1, payload=b"\0" * 7),
        DecodeError,
        "of another size than the recipe's (expected 8 bytes, got 7 bytes)",
    ),
    "an unknown package type": (bytes([0, 3, ord("Z")]), DecodeError, "unknown package type 90"),
}


@pytest.mark.parametrize("bad", BAD_PACKAGES, ids=list(BAD_PACKAGES))
def test_a_protocol_error_ends_iteration_with_that_error_after_the_packages_before_it(bad: str) -> None:
    package, error, says = BAD_PACKAGES[bad]
    peer = HostilePeer()
    got: list[float] = []
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        client.setup_outputs(["timestamp"], 125)
        client.start()
        peer.send(peer.data(1.0) + peer.data(2.0) + package)  # one read: the good ones are kept
        with pytest.raises(error, match=re.escape(says)):
            for record in client:
                got.append(record.timestamp)
        assert isinstance(client.connection_lost, error)
    assert got == [1.0, 2.0]
    peer.close()


@pytest.mark.parametrize("bad", BAD_PACKAGES, ids=list(BAD_PACKAGES))
def test_the_asyncio_client_raises_a_protocol_error_instead_of_ending_quietly(bad: str) -> None:
    package, error, says = BAD_PACKAGES[bad]
    peer = HostilePeer()
    got: list[float] = []

    async def run() -> None:
        async with AsyncRtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
            await client.setup_outputs(["timestamp"], 125)
            await client.start()
            peer.send(peer.data(1.0))
            got.append((await client.receive()).timestamp)
            peer.send(package)  # a read of its own
            async for record in client:
                got.append(record.timestamp)

    with pytest.raises(error, match=re.escape(says)):  # the same error the blocking client raises
        asyncio.run(run())
    assert got == [1.0]
    peer.close()
