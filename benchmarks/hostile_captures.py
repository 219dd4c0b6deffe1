"""Big hostile captures, written fast (struct, no dpkt): for benchmarks/faults_capture.py and the tests.

Each writes a classic pcap (Ethernet, IPv4, TCP; checksums left 0 as offloading NICs
capture them): a SYN flood to ports nobody decodes, many short RTDE connections, a
stream of 1-byte segments each after a 1-byte hole, a 50002 script-sender stream
with or without newlines.
"""

from __future__ import annotations

import struct
import sys
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.append(str(ROOT))

SYN, FIN, ACK, PSH = 0x02, 0x01, 0x10, 0x08
_RECORD = struct.Struct("<IIII")
_IP = struct.Struct(">BBHHHBBH4s4s")
_TCP = struct.Struct(">HHIIBBHHH")
_ETH = b"\x04" * 6 + b"\x02" * 6 + b"\x08\x00"


def _frame(src: bytes, sport: int, dst: bytes, dport: int, seq: int, flags: int, payload: bytes) -> bytes:
    tcp = _TCP.pack(sport, dport, seq & 0xFFFFFFFF, 0, 5 << 4, flags, 65535, 0, 0)
    ip = _IP.pack(0x45, 0, 20 + len(tcp) + len(payload), 0, 0x4000, 64, 6, 0, src, dst)
    return _ETH + ip + tcp + payload


def _ip(a: int) -> bytes:
    return struct.pack(">I", (10 << 24) | (a & 0xFFFFFF))


def write(path: Path, frames: Iterator[tuple[float, bytes]]) -> Path:
    """Frames (time, bytes) to a pcap file, streamed."""
    with open(path, "wb", buffering=1 << 20) as out:
        out.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1))
        for time, frame in frames:
            sec = int(time)
            out.write(_RECORD.pack(sec, int((time - sec) * 1e6), len(frame), len(frame)))
            out.write(frame)
    return path


def syn_flood(path: Path, count: int) -> Path:
    """`count` SYNs from as many sources to ports nobody decodes (a port scan)."""

    def frames() -> Iterator[tuple[float, bytes]]:
        dst = _ip(0x010101)
        for i in range(count):
            yield (
                1_700_000_000 + i * 1e-5,
                _frame(_ip(i + 2), 1024 + i % 60000, dst, 1 + i % 1000, i, SYN, b""),
            )

    return write(path, frames())


def rtde_connections(path: Path, count: int, packages: int = 4) -> Path:
    """`count` RTDE sessions one after another: handshake, setup, data, FIN both ways."""
    from rtde_spec import Catalogue, build
    from tests.capture_files import SMALL, rtde_packages

    cat = Catalogue.builtin()
    types = [cat.get(n, "output").type for n in SMALL]  # type: ignore[union-attr]
    client_says = [
        build("request_protocol_version", protocol_version=2),
        build("setup_outputs_v2", output_frequency=500.0, variable_names=list(SMALL)),
        build("start"),
    ]
    server_says = [
        build("request_protocol_version_reply", accepted=True),
        build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types),
        build("start_reply", accepted=True),
    ]
    data = rtde_packages(packages)

    def frames() -> Iterator[tuple[float, bytes]]:
        server = _ip(0x0A0A0A)
        t = 1_700_000_000.0
        for i in range(count):
            client, port = _ip(0x020000 + i % 60000), 1024 + i % 60000
            cseq, sseq = 1000, 5000
            yield t, _frame(client, port, server, 30004, cseq, SYN, b"")
            yield t, _frame(server, 30004, client, port, sseq, SYN | ACK, b"")
            cseq, sseq = cseq + 1, sseq + 1
            for ask, answer in zip(client_says, server_says, strict=True):
                t += 1e-4
                yield t, _frame(client, port, server, 30004, cseq, ACK | PSH, ask)
                yield t, _frame(server, 30004, client, port, sseq, ACK | PSH, answer)
                cseq, sseq = cseq + len(ask), sseq + len(answer)
            for package in data:
                t += 2e-3
                yield t, _frame(server, 30004, client, port, sseq, ACK | PSH, package)
                sseq += len(package)
            yield t, _frame(client, port, server, 30004, cseq, FIN | ACK, b"")
            yield t, _frame(server, 30004, client, port, sseq, FIN | ACK, b"")
            t += 1e-3

    return write(path, frames())


def holes(path: Path, count: int) -> Path:
    """An RTDE session whose data arrives as `count` 1-byte segments, each after a 1-byte hole."""
    from tests.capture_files import rtde_packages

    stream = b"".join(rtde_packages(count * 2 // 64 + 2))

    def frames() -> Iterator[tuple[float, bytes]]:
        client, server = _ip(2), _ip(10)
        t = 1_700_000_000.0
        yield t, _frame(client, 51000, server, 30004, 999, SYN, b"")
        yield t, _frame(server, 30004, client, 51000, 4999, SYN | ACK, b"")
        for i in range(count):
            t += 1e-4
            yield (
                t,
                _frame(
                    server, 30004, client, 51000, 5000 + 2 * i + 1, ACK | PSH, stream[2 * i + 1 : 2 * i + 2]
                ),
            )

    return write(path, frames())


def script_stream(path: Path, size: int, newlines: bool, from_robot: bool = True) -> Path:
    """`size` bytes on a 50002 script-sender connection: newlines only, or text with none."""
    block = (b"\n" if newlines else b"x") * 1400

    def frames() -> Iterator[tuple[float, bytes]]:
        robot, driver = _ip(10), _ip(2)
        src, sport, dst, dport = (
            (robot, 40000, driver, 50002) if from_robot else (driver, 50002, robot, 40000)
        )
        t = 1_700_000_000.0
        yield t, _frame(robot, 40000, driver, 50002, 999, SYN, b"")
        yield t, _frame(driver, 50002, robot, 40000, 4999, SYN | ACK, b"")
        seq = 1000 if from_robot else 5000
        for _ in range(size // len(block)):
            t += 1e-4
            yield t, _frame(src, sport, dst, dport, seq, ACK | PSH, block)
            seq += len(block)

    return write(path, frames())


def byte_by_byte(path: Path, size: int, port: int = 30003) -> Path:
    """`size` bytes that hold no package, sent by the server of `port` one byte per segment, captured
    from the middle (no handshake): each decoder's search for a boundary sees every byte arrive."""
    data = bytes((i * 7919 + 13) % 251 for i in range(size))

    def frames() -> Iterator[tuple[float, bytes]]:
        server, client = _ip(10), _ip(2)
        for i in range(size):
            frame = _frame(server, port, client, 40000, 5000 + i, ACK, data[i : i + 1])
            yield 1_700_000_000 + i * 1e-5, frame

    return write(path, frames())
