"""Frames out of pcap and pcapng files, read with `struct` in large blocks.

A general packet library builds an object per header per frame; for a capture of
hundreds of thousands of small RTDE packages that is most of the decode time.
Here each record costs one header unpack and one slice. Classic pcap in either
byte order with micro- or nanosecond stamps; pcapng section, interface (link
type, timestamp resolution), enhanced and simple packet blocks, in either byte
order, several interfaces and sections. Other blocks are skipped.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import IO

from rtde_spec.errors import UsageError

BLOCK = 8 << 20
PCAPNG_SHB = 0x0A0D0D0A
PCAPNG_BYTE_ORDER = 0x1A2B3C4D
PCAP_MAGIC = {  # magic as read little-endian -> (byte order, seconds per timestamp unit)
    0xA1B2C3D4: ("<", 1e-6),
    0xA1B23C4D: ("<", 1e-9),
    0xD4C3B2A1: (">", 1e-6),
    0x4D3CB2A1: (">", 1e-9),
}

Frame = tuple[float, int, bytes]  # (capture time, link type, frame bytes)


class _Reader:
    """A file read in blocks; `take(n)` returns the next n bytes (fewer at the end)."""

    def __init__(self, f: IO[bytes]) -> None:
        self.f = f
        self.buf = b""
        self.pos = 0
        self.consumed = 0  # file offset of buf[0]

    def take(self, n: int) -> bytes:
        if len(self.buf) - self.pos < n:
            self.consumed += self.pos
            self.buf = self.buf[self.pos :] + self.f.read(max(BLOCK, n))
            self.pos = 0
        out = self.buf[self.pos : self.pos + n]
        self.pos += len(out)
        return out

    def tell(self) -> int:
        return self.consumed + self.pos


def frames(f: IO[bytes], name: str, stats: dict[str, int]) -> Iterator[Frame]:
    """Every frame of the capture in file order. `stats['truncated']` counts a cut-off last record."""
    reader = _Reader(f)
    head = reader.take(4)
    if len(head) < 4:
        raise UsageError("not a pcap or pcapng file (shorter than a header)", subject=f"file {name}")
    magic = int.from_bytes(head, "little")
    if magic == PCAPNG_SHB:
        yield from _pcapng(reader, head, name, stats)
    elif magic in PCAP_MAGIC:
        yield from _pcap(reader, *PCAP_MAGIC[magic], name, stats)
    else:
        raise UsageError(f"not a pcap or pcapng file (magic {head.hex()})", subject=f"file {name}")


def _pcap(reader: _Reader, order: str, unit: float, name: str, stats: dict[str, int]) -> Iterator[Frame]:
    rest = reader.take(20)
    if len(rest) < 20:
        raise UsageError("not a pcap file (its header is cut off)", subject=f"file {name}")
    linktype = struct.unpack(order + "I", rest[16:20])[0] & 0x0FFFFFFF  # upper bits: FCS flags
    record = struct.Struct(order + "IIII")
    take = reader.take
    while True:
        head = take(16)
        if len(head) < 16:
            if head:
                stats["truncated"] = stats.get("truncated", 0) + 1
            return
        sec, frac, caplen, _ = record.unpack(head)
        data = take(caplen)
        if len(data) < caplen:
            stats["truncated"] = stats.get("truncated", 0) + 1
            return
        yield sec + frac * unit, linktype, data


def _pcapng(reader: _Reader, first: bytes, name: str, stats: dict[str, int]) -> Iterator[Frame]:
    order = "<"
    interfaces: list[tuple[int, float]] = []  # (link type, seconds per timestamp unit)
    head = first + reader.take(8)
    while len(head) == 12:
        btype_le = int.from_bytes(head[:4], "little")
        if btype_le == PCAPNG_SHB:  # a new section: byte order and interfaces start over
            order = "<" if int.from_bytes(head[8:12], "little") == PCAPNG_BYTE_ORDER else ">"
            interfaces = []
        btype, length = struct.unpack(order + "II", head[:8])
        if length < 12 or length % 4:
            raise UsageError(
                f"pcapng block of length {length} at byte {reader.tell() - 12}", subject=f"file {name}"
            )
        body = head[8:] + reader.take(length - 12)
        if len(body) < length - 8:
            stats["truncated"] = stats.get("truncated", 0) + 1
            return
        if btype == 1:  # interface description
            linktype = struct.unpack(order + "H", body[:2])[0]
            interfaces.append((linktype, _resolution(body[8 : length - 12], order)))
        elif btype == 6:  # enhanced packet
            iface, high, low, caplen = struct.unpack(order + "IIII", body[:16])
            linktype, unit = interfaces[iface] if iface < len(interfaces) else (-1, 1e-6)
            yield ((high << 32) | low) * unit, linktype, body[20 : 20 + caplen]
        elif btype == 3 and interfaces:  # simple packet: no time, interface 0, snap-length cut
            (origlen,) = struct.unpack(order + "I", body[:4])
            yield 0.0, interfaces[0][0], body[4 : 4 + min(origlen, length - 16)]
        head = reader.take(12)
    if head:
        stats["truncated"] = stats.get("truncated", 0) + 1


def _resolution(options: bytes, order: str) -> float:
    """Seconds per timestamp unit from an interface's if_tsresol option (default microseconds)."""
    pos = 0
    while pos + 4 <= len(options):
        code, size = struct.unpack(order + "HH", options[pos : pos + 4])
        if code == 0:
            break
        if code == 9 and size >= 1:
            value = options[pos + 4]
            return 2.0 ** -(value & 0x7F) if value & 0x80 else 10.0**-value
        pos += 4 + size + (-size % 4)
    return 1e-6
