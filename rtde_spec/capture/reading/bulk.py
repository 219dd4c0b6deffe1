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
from rtde_spec.capture.reading.pcapfile import Records

ETHERNET, IPV4, TCP = 1, 0x0800, 6
ETH, IP_MIN, TCP_MIN = 14, 20, 20
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
    bare: Bare | None = None  # the connection's segments without data between the packages


@dataclass
class Bare:
    """Segments of the run's connection without data or SYN, FIN, RST (the peer's ACKs), found
    between the run's packages: routing them is all they do, so a run goes on over them. Kept
    for `packets.expand`, which gives them back in their places when the run is read one by one."""

    before: Any  # numpy int64: how many of the run's packages come before each
    times: Any
    reverse: Any  # numpy bool: sent by the run's receiver
    seq: Any
    ack: Any
    flags: Any


def runs(records: Records) -> list[tuple[int, int, Any]]:
    """(first, end, data) of every run of at least MIN_RUN data frames in order on one connection
    direction: its records first..end-1, of which `data` (record indexes) are its packages and the
    rest segments without data of the same connection (None: all are packages)."""
    import numpy as np

    n = len(records.offsets)
    if n < MIN_RUN or not (records.links == ETHERNET).any():
        return []
    u8 = np.frombuffer(records.buf, dtype=np.uint8)
    last = len(u8) - 1
    off = records.offsets
    cap_end = off + records.lengths

    def at(index: Any) -> Any:
        return u8[np.minimum(index, last)].astype(np.int64)

    def be(index: Any, width: int) -> Any:
        value = at(index)
        for k in range(1, width):
            value = (value << 8) | at(index + k)
        return value

    ip = off + ETH
    ok = (records.links == ETHERNET) & (cap_end >= ip + IP_MIN + TCP_MIN)
    ok &= be(off + 12, 2) == IPV4
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
    ends_a, ends_b = (src << 16) | (ports >> 16), (dst << 16) | (ports & 0xFFFF)
    low, high = np.minimum(ends_a, ends_b), np.maximum(ends_a, ends_b)  # the connection, either way
    before = np.maximum.accumulate(np.where(ok, np.arange(n), 0))  # the last data record up to each
    bare &= (before < np.arange(n)) & (low == low[before]) & (high == high[before]) & ok[before]
    breaks = np.cumsum(~ok & ~bare)  # records that end a run, up to each
    prefix = be(pay, PREFIX_BYTES)  # size, type and recipe id
    key = [src, dst, ports, size, prefix]
    seq = be(tcp + 4, 4)
    return _grouped(data, breaks, seq, size, key)


def _grouped(data: Any, breaks: Any, seq: Any, size: Any, key: list[Any]) -> list[tuple[int, int, Any]]:
    """The runs among the data records `data`: each follows the one before in sequence, with the
    same `key`, and no record that ends a run between them (`breaks`: how many up to each)."""
    import numpy as np

    a, b = data[:-1], data[1:]  # each data record and the next
    follows = (breaks[b - 1] == breaks[a]) & (seq[b] == (seq[a] + size[a]) % (1 << 32))
    for column in key:
        follows &= column[b] == column[a]
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


def run_of(records: Records, first: int, end: int, picks: Any = None) -> DataRun:
    """The DataRun of records first..end-1 (as `runs` found them; `picks`: its packages' records
    where segments without data come between them)."""
    import numpy as np

    buf = records.buf
    ip = int(records.offsets[first]) + ETH
    tcp = ip + (buf[ip] & 0x0F) * 4
    pay = tcp + (buf[tcp + 12] >> 4) * 4
    size = int.from_bytes(buf[pay + SIZE_AT : pay + SIZE_AT + SIZE_BYTES], "big")
    u8 = np.frombuffer(buf, dtype=np.uint8)  # header lengths may differ frame to frame (options)
    offs = records.offsets[first:end] if picks is None else records.offsets[picks]
    ihl = (u8[offs + ETH] & 0x0F).astype(np.int64) * 4
    doff = (u8[offs + ETH + ihl + 12] >> 4).astype(np.int64) * 4
    starts = offs + ETH + ihl + doff
    stride = int(starts[1] - starts[0]) if len(starts) > 1 else size
    if (np.diff(starts) == stride).all() and stride >= size:  # records evenly spaced: a strided view
        rows = np.ndarray(
            (len(starts), size), dtype=np.uint8, buffer=buf, offset=int(starts[0]), strides=(stride, 1)
        )
    else:
        rows = u8[starts[:, None] + np.arange(size)]  # gathered (a copy)
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
        None if picks is None else _bare(records, u8, first, end, picks, buf[ip + 12 : ip + 16]),
    )


def _bare(records: Records, u8: Any, first: int, end: int, picks: Any, src: bytes) -> Bare:
    """The segments without data among records first..end-1 (all but `picks`), as `expand` needs them."""
    import numpy as np

    others = np.setdiff1d(np.arange(first, end), picks, assume_unique=True)
    ip = records.offsets[others] + ETH
    tcp = ip + (u8[ip] & 0x0F).astype(np.int64) * 4
    word = np.array([1 << 24, 1 << 16, 1 << 8, 1], dtype=np.int64)
    seq, ack = ((u8[(tcp + at)[:, None] + np.arange(4)] * word).sum(axis=1) for at in (4, 8))
    reverse = (u8[(ip + 12)[:, None] + np.arange(4)] != np.frombuffer(src, dtype=np.uint8)).any(axis=1)
    before = np.searchsorted(picks, others)
    return Bare(before, records.times[others], reverse, seq, ack, u8[tcp + 13].astype(np.int64))
