"""Clients against a controller that hangs up inside a package, or sends the largest text message.

A package cut off by the close is data lost: it is reported (a DecodeError saying how much of
it came, from iteration and `connection_lost`), never a quiet end; a close between packages
still ends iteration quietly. Real sockets on 127.0.0.1 play the controller.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import struct
import threading
import time
from typing import Any

import pytest

from rtde_spec import AsyncRtdeClient, PrimaryClient, RtdeClient
from rtde_spec._generated import primary_models as pgen
from rtde_spec.errors import DecodeError, RtdeConnectionError
from rtde_spec.primary.codec import encode_message
from tests.faults.clients_peer import HostilePeer

DATA_SIZE = 12  # a data package of one DOUBLE: size, type, recipe id, 8 bytes


def stream_then_cut(peer: HostilePeer, cut: int) -> None:
    """Three data packages, then `cut` bytes of a fourth, then the connection closes."""
    peer.send(peer.data(1.0) + peer.data(2.0) + peer.data(3.0) + peer.data(4.0)[:cut])
    assert peer.conn is not None
    peer.conn.shutdown(socket.SHUT_RDWR)
    peer.close()


@pytest.mark.parametrize(("cut", "of"), [(7, "12 bytes"), (1, ">= 3 bytes")])
def test_a_package_cut_off_by_the_close_is_reported_by_the_blocking_client(cut: int, of: str) -> None:
    peer = HostilePeer()
    got: list[float] = []
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        client.setup_outputs(["timestamp"], 125)
        client.start()
        stream_then_cut(peer, cut)
        with pytest.raises(DecodeError, match=f"connection closed inside a package: {cut} of {of}"):
            for record in client:
                got.append(record.timestamp)
        assert isinstance(client.connection_lost, DecodeError)
        assert "127.0.0.1" in str(client.connection_lost)
    assert got == [1.0, 2.0, 3.0]
    # a close between packages is still the quiet end of iteration
    peer = HostilePeer()
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        client.setup_outputs(["timestamp"], 125)
        client.start()
        stream_then_cut(peer, 0)
        assert [r.timestamp for r in client] == [1.0, 2.0, 3.0]
        assert isinstance(client.connection_lost, RtdeConnectionError)


def test_a_package_cut_off_by_the_close_is_reported_by_the_asyncio_client() -> None:
    async def run(cut: int, got: list[float]) -> BaseException | None:
        peer = HostilePeer()
        async with AsyncRtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
            await client.setup_outputs(["timestamp"], 125)
            await client.start()
            stream_then_cut(peer, cut)
            async for record in client:
                got.append(record.timestamp)
            return client.connection_lost

    got: list[float] = []
    with pytest.raises(DecodeError, match="connection closed inside a package: 7 of 12 bytes"):
        asyncio.run(run(7, got))
    assert got == [1.0, 2.0, 3.0]
    got.clear()
    assert isinstance(asyncio.run(run(0, got)), RtdeConnectionError) and got == [1.0, 2.0, 3.0]


def test_a_message_cut_off_by_the_close_is_reported_by_the_primary_client() -> None:
    version = encode_message(
        pgen.VersionMessage(
            timestamp=1,
            source=-2,
            project_name="URControl",
            major_version=5,
            minor_version=15,
            bugfix_version=0,
            build_number=0,
            build_date="today",
        )
    )
    server = socket.create_server(("127.0.0.1", 0))

    def serve(cut: int) -> None:
        conn, _ = server.accept()
        conn.sendall(version + version[:cut])
        conn.shutdown(socket.SHUT_RDWR)
        conn.close()

    for cut, error in ((10, True), (0, False)):
        thread = threading.Thread(target=serve, args=(cut,), daemon=True)
        thread.start()
        got = []
        with PrimaryClient("127.0.0.1", server.getsockname()[1], timeout=2.0) as client:
            if error:
                with pytest.raises(
                    DecodeError, match=f"connection closed inside a message: 10 of {len(version)} bytes"
                ):
                    for message in client:
                        got.append(message.NAME)
            else:
                got = [message.NAME for message in client]
        assert got == ["version_message"]
        thread.join(5)
    server.close()


LONGEST = 65535  # the largest package the uint16 size field can count


def longest_text(level: int = 3) -> bytes:
    """A protocol-1 text message of 65,535 bytes: level, then the text to the end of the package."""
    return struct.pack(">HBB", LONGEST, ord("M"), level) + b"x" * (LONGEST - 4)


def test_a_65535_byte_text_message_decodes_between_data_packages(caplog: Any) -> None:
    """The longest text message a protocol-1 controller can send arrives whole, in several reads,
    between data packages; a text one byte too long for the size field (its size wraps to 3)
    is an error naming the fields it lacks, not "expected None"."""
    caplog.set_level(logging.INFO, logger="rtde_spec.client")
    peer = HostilePeer(accept_versions=(1,))
    with RtdeClient("127.0.0.1", peer.port, timeout=2.0) as client:
        assert client.protocol_version == 1
        client.setup_outputs(["timestamp"], 125)
        client.start()
        text = longest_text()
        peer.send(peer.data(1.0) + text[:30000])
        time.sleep(0.1)
        peer.send(text[30000:] + peer.data(2.0))
        assert [client.receive().timestamp for _ in range(2)] == [1.0, 2.0]
        assert client.connection_lost is None
        texts = [r.getMessage() for r in caplog.records if "xxxx" in r.getMessage()]
        assert len(texts) == 1 and texts[0].count("x") == LONGEST - 4
        # 65,535 bytes of text need a size of 65,539, which wraps to 3: a package of its header only
        peer.send(struct.pack(">HBB", (LONGEST + 4) & 0xFFFF, ord("M"), 3) + b"x" * 40)
        deadline = time.monotonic() + 5
        while client.connection_lost is None and time.monotonic() < deadline:
            time.sleep(0.01)
        lost = client.connection_lost
        assert isinstance(lost, DecodeError) and lost.field == "message_type"
        assert "expected None" not in str(lost) and "message_type, message" in str(lost)
    peer.close()
