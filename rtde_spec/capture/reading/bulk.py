"""Whole runs of RTDE data segments found in a block of a capture file with numpy.

At 500 Hz nearly every frame of an RTDE capture is Ethernet, IPv4, TCP, one whole data
package of the same size, the sequence numbers following on. Per block of the file the
record headers are walked once; then the IP and TCP headers of every frame are read
as numpy columns, runs of such frames are marked, and each run's payloads are handed on
as a numpy view of the file (rows of one package each), copied only when decoded.
Every other frame is handed back whole, to be read one by one.
"""

from __future__ import annotations

import socket
import struct
from dataclasses import dataclass
from typing import Any

from rtde_spec._generated.constants import (
    DATA_PACKAGE_PREFIX_FORMAT,
    DATA_PACKAGE_PREFIX_OFFSETS,
    DATA_PACKAGE_TYPE,
)
from rtde_spec.capture.reading.link_types import COOKED, ETHERNET, LINK_HEADERS, LOOPBACK, RAW_IP
from rtde_spec.capture.reading.pcapfile import Records
from rtde_spec.capture.reading.tunnels import IPV4, VLAN

TCP, VLAN_TAG = 6, VLAN[0]  # one 802.1Q tag (more, or 802.1ad: frame by frame)
ETH, IP_MIN, TCP_MIN = LINK_HEADERS[ETHERNET], 20, 20
NOT_DATA = 0x07  # FIN, SYN, RST
MIN_RUN = 16  # shorter runs are handed back frame by frame
SIZE_AT, TYPE_AT, _ = DATA_PACKAGE_PREFIX_OFFSETS  # where a data package says its size and type
SIZE_BYTES = TYPE_AT - SIZE_AT
PREFIX_BYTES = struct.calcsize(DATA_PACKAGE_PREFIX_FORMAT)


@dataclass
class DataRun:
    """Frames in order on one connection direction, each one whole data package of `size` bytes."""

    src: str
    sport: int
    dst: str
    dport: int
    seq: int  # of the first frame
    size: int
    times: Any  # numpy float64, one per package
    rows: Any  # numpy uint8 (packages, size): one package per row
    bare: BareSegments | None = None  # the connection's segments without data between the packages


@dataclass
class BareSegments:
    """Segments of the run's connection without data or SYN, FIN, RST (the peer's ACKs), found
    between the run's packages: routing them is all they do, so a run goes on over them. Read
    (`columns`) only for `packets.expand`, which gives them back in their places when the run is
    read one by one (rarely: a run its connection cannot take whole)."""

    records: Records
    first: int
    end: int
    picks: Any  # the run's packages' records; the others in first..end-1 are these
    src: bytes  # the run's sender's address

    def columns(self) -> tuple[Any, ...]:
        """How many of the run's packages come before each, its time, whether the run's receiver
        sent it, its sequence and acknowledgment numbers and its flags (numpy columns)."""
        import numpy as np

        records, u8 = self.records, np.frombuffer(self.records.buf, dtype=np.uint8)
        others = np.setdiff1d(np.arange(self.first, self.end), self.picks, assume_unique=True)
        ip, _ = ip_offsets(u8, records.offsets[others], records.links[others])
        tcp = ip + (u8[ip] & 0x0F).astype(np.int64) * 4
        word = np.array([1 << 24, 1 << 16, 1 << 8, 1], dtype=np.int64)
        seq, ack = ((u8[(tcp + at)[:, None] + np.arange(4)] * word).sum(axis=1) for at in (4, 8))
        src = np.frombuffer(self.src, dtype=np.uint8)
        reverse = (u8[(ip + 12)[:, None] + np.arange(4)] != src).any(axis=1)
        before = np.searchsorted(self.picks, others)
        return before, records.times[others], reverse, seq, ack, u8[tcp + 13].astype(np.int64)


def runs(records: Records) -> list[tuple[int, int, Any]]:
    """(first, end, data) of every run of at least MIN_RUN data frames in order on one connection
    direction: its records first..end-1, of which `data` (record indexes) are its packages and the
    rest segments without data of the same connection (None: all are packages)."""
    import numpy as np

    n = len(records.offsets)
    if n < MIN_RUN:
        return []
    u8 = np.frombuffer(records.buf, dtype=np.uint8)
    last = len(u8) - 1
    off = records.offsets
    cap_end = off + records.lengths
    ip, ok = ip_offsets(u8, off, records.links)

    def at(index: Any) -> Any:
        return u8[np.minimum(index, last)].astype(np.int64)

    def be(index: Any, width: int) -> Any:
        value = at(index)
        for k in range(1, width):
            value = (value << 8) | at(index + k)
        return value

    ok &= cap_end >= ip + IP_MIN + TCP_MIN
    ok &= (at(ip) >> 4) == 4
    ok &= at(ip + 9) == TCP
    ok &= (be(ip + 6, 2) & 0x3FFF) == 0  # not a fragment
    ihl = (at(ip) & 0x0F) * 4
    tcp = ip + ihl
    ok &= (ihl >= IP_MIN) & (tcp + TCP_MIN <= cap_end)
    pay = tcp + (at(tcp + 12) >> 4) * 4
    total = be(ip + 2, 2)
    end = np.where(total == 0, cap_end, ip + total)  # 0: segmentation offload, the frame's length
    size = end - pay
    ok &= (end <= cap_end) & ((at(tcp + 13) & NOT_DATA) == 0) & ((at(tcp + 12) >> 4) * 4 >= TCP_MIN)
    bare = ok & (size == 0)
    ok &= (size > 4) & (at(pay + TYPE_AT) == DATA_PACKAGE_TYPE) & (be(pay + SIZE_AT, SIZE_BYTES) == size)
    data = np.flatnonzero(ok)
    if len(data) < MIN_RUN:
        return []
    src, dst, ports = be(ip + 12, 4), be(ip + 16, 4), be(tcp, 4)
    between = None  # the records between each data record and the next end no run (all data: none)
    if len(data) < n:
        if bare.any():
            ends_a, ends_b = (src << 16) | (ports >> 16), (dst << 16) | (ports & 0xFFFF)
            low, high = np.minimum(ends_a, ends_b), np.maximum(ends_a, ends_b)  # the connection
            before = np.maximum.accumulate(np.where(ok, np.arange(n), 0))  # the last data record up to each
            bare &= (before < np.arange(n)) & (low == low[before]) & (high == high[before]) & ok[before]
        breaks = np.cumsum(~ok & ~bare)  # records that end a run, up to each
        between = breaks[data[1:] - 1] == breaks[data[:-1]]
    key = [src, dst, ports, size, be(pay, PREFIX_BYTES)]  # addresses, ports, size, prefix
    return _grouped(data, between, be(tcp + 4, 4), size, key, len(data) < n)


def _grouped(
    data: Any, between: Any, seq: Any, size: Any, key: list[Any], picked: bool
) -> list[tuple[int, int, Any]]:
    """The runs among the data records `data` (`picked`: not all the records): each follows the
    one before in sequence, with the same `key`, and nothing that ends a run `between` them."""
    import numpy as np

    if picked:  # the data records' values, side by side
        seq, size, key = seq[data], size[data], [column[data] for column in key]
    follows = seq[1:] == (seq[:-1] + size[:-1]) % (1 << 32)
    if between is not None:
        follows &= between
    for column in key:
        follows &= column[1:] == column[:-1]
    # run boundaries: a data record that does not follow the one before starts a new run
    starts = np.flatnonzero(np.concatenate(([True], ~follows)))
    ends = np.append(starts[1:], len(data))
    keep = ends - starts >= MIN_RUN
    found = []
    for start, stop in zip(starts[keep].tolist(), ends[keep].tolist(), strict=True):
        first, final = int(data[start]), int(data[stop - 1])
        picks = data[start:stop] if final - first + 1 > stop - start else None
        found.append((first, final + 1, picks))
    return found


def _gathered(buf: Any, starts: list[int], size: int) -> Any:
    """The packages at `starts` copied into rows (the peer's ACKs come between some of them): one
    view copied a package; a numpy index of every byte cost 4x as much, slices joined 2x."""
    import numpy as np

    out = np.empty((len(starts), size), dtype=np.uint8)
    with memoryview(out.data) as whole, whole.cast("B") as into, memoryview(buf) as source:  # released: a
        at = 0  # mapped file with a view of it left cannot be closed
        for start in starts:
            into[at : at + size] = source[start : start + size]
            at += size
    return out


def ip_offsets(u8: Any, offsets: Any, links: Any) -> tuple[Any, Any]:
    """Where each record's IPv4 header starts, and whether it has one after a link header read
    here: Ethernet (and one 802.1Q tag, as a switch's mirror port keeps it), Linux cooked v1 and
    v2 (`tcpdump -i any`), BSD loopback, raw IP. Other frames are read one by one (packets.py)."""
    import numpy as np

    last = len(u8) - 2

    def be2(index: Any) -> Any:
        index = np.minimum(index, last)
        return (u8[index].astype(np.int64) << 8) | u8[index + 1]

    l2 = np.full(len(offsets), -1, dtype=np.int64)
    ethernet = links == ETHERNET
    if ethernet.any():
        kind = be2(offsets + 12)
        l2[ethernet & (kind == IPV4)] = ETH
        tagged = ethernet & (kind == VLAN_TAG)
        if tagged.any():
            l2[tagged & (be2(offsets + 16) == IPV4)] = ETH + 4
    for link, (at, size) in COOKED.items():
        mine = links == link
        if mine.any():
            l2[mine & (be2(offsets + at) == IPV4)] = size
    for kinds, size in ((LOOPBACK, 4), (RAW_IP, 0)):
        for kind in kinds:
            mine = links == kind
            if mine.any():
                l2[mine] = size
    return offsets + np.maximum(l2, 0), l2 >= 0


def run_of(records: Records, first: int, end: int, picks: Any = None) -> DataRun:
    """The DataRun of records first..end-1 (as `runs` found them; `picks`: its packages' records
    where segments without data come between them)."""
    import numpy as np

    buf = records.buf
    u8 = np.frombuffer(buf, dtype=np.uint8)  # header lengths may differ frame to frame (options)
    chosen = slice(first, end) if picks is None else picks
    ips, _ = ip_offsets(u8, records.offsets[chosen], records.links[chosen])
    ip = int(ips[0])
    tcp = ip + (buf[ip] & 0x0F) * 4
    pay = tcp + (buf[tcp + 12] >> 4) * 4
    size = int.from_bytes(buf[pay + SIZE_AT : pay + SIZE_AT + SIZE_BYTES], "big")
    ihl = (u8[ips] & 0x0F).astype(np.int64) * 4
    doff = (u8[ips + ihl + 12] >> 4).astype(np.int64) * 4
    starts = ips + ihl + doff
    stride = int(starts[1] - starts[0]) if len(starts) > 1 else size
    if (np.diff(starts) == stride).all() and stride >= size:  # records evenly spaced: a strided view
        rows = np.ndarray(
            (len(starts), size), dtype=np.uint8, buffer=buf, offset=int(starts[0]), strides=(stride, 1)
        )
    else:
        rows = _gathered(buf, starts.tolist(), size)
    sport, dport, seq = struct.unpack_from(">HHI", buf, tcp)
    return DataRun(
        socket.inet_ntop(socket.AF_INET, buf[ip + 12 : ip + 16]),
        sport,
        socket.inet_ntop(socket.AF_INET, buf[ip + 16 : ip + 20]),
        dport,
        seq,
        size,
        records.times[first:end] if picks is None else records.times[picks],
        rows,
        None if picks is None else BareSegments(records, first, end, picks, bytes(buf[ip + 12 : ip + 16])),
    )
