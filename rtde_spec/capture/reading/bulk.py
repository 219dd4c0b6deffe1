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


def runs(records: Records) -> list[tuple[int, int]]:
    """(first, end) record indexes of every run of at least MIN_RUN data frames."""
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
    ok &= (end <= cap_end) & (size > 4) & ((at(tcp + 13) & NOT_DATA) == 0)
    ok &= (at(pay + TYPE_AT) == DATA_PACKAGE_TYPE) & (be(pay + SIZE_AT, SIZE_BYTES) == size)
    if not ok.any():
        return []
    prefix = be(pay, PREFIX_BYTES)  # size, type and recipe id
    key = [be(ip + 12, 4), be(ip + 16, 4), be(tcp, 4), size, prefix]  # addresses, ports, size, prefix
    seq = be(tcp + 4, 4)
    follows = ok[1:] & ok[:-1] & (seq[1:] == (seq[:-1] + size[:-1]) % (1 << 32))
    for column in key:
        follows &= column[1:] == column[:-1]
    # run boundaries: a record that does not follow its predecessor starts a new piece
    starts = np.flatnonzero(np.concatenate(([True], ~follows)))
    ends = np.append(starts[1:], n)
    keep = ok[starts] & (ends - starts >= MIN_RUN)
    return list(zip(starts[keep].tolist(), ends[keep].tolist(), strict=True))


def run_of(records: Records, first: int, end: int) -> DataRun:
    """The DataRun of records first..end-1 (as `runs` found them)."""
    import numpy as np

    buf = records.buf
    ip = int(records.offsets[first]) + ETH
    tcp = ip + (buf[ip] & 0x0F) * 4
    pay = tcp + (buf[tcp + 12] >> 4) * 4
    size = int.from_bytes(buf[pay + SIZE_AT : pay + SIZE_AT + SIZE_BYTES], "big")
    u8 = np.frombuffer(buf, dtype=np.uint8)  # header lengths may differ frame to frame (options)
    offs = records.offsets[first:end]
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
        records.times[first:end],
        rows,
    )
