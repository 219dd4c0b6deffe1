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
NOT_DATA, ACK = 0x07, 0x10  # FIN, SYN, RST; ACK
MIN_RUN = 16  # shorter runs are handed back frame by frame
SIZE_AT, TYPE_AT, _ = DATA_PACKAGE_PREFIX_OFFSETS  # where a data package says its size and type
SIZE_BYTES = TYPE_AT - SIZE_AT
PREFIX_BYTES = struct.calcsize(DATA_PACKAGE_PREFIX_FORMAT)


@dataclass
class DataRun:
    """Frames in order on one connection direction, each one whole data package (or, on a port of
    fixed-size records, one whole record) of `size` bytes."""

    src: str
    sport: int
    dst: str
    dport: int
    seq: int  # of the first frame
    size: int
    times: Any  # numpy float64, one per package
    rows: Any  # numpy uint8 (packages, size): one package per row
    bare: BareSegments | None = None  # the connection's segments without data between the packages
    frames: tuple[Records, Any] | None = None  # (records, the run's): read only when it is expanded

    def acks(self) -> list[int] | None:
        """Each package's acknowledgment number (-1: no ACK flag), for `packets.expand`."""
        if self.frames is None:
            return None
        import numpy as np

        records, chosen = self.frames
        u8, _, tcp = _tcp_at(np, records, chosen)
        return np.where(u8[tcp + 13] & ACK, _word(np, u8, tcp + 8), -1).tolist()  # type: ignore[no-any-return]


@dataclass
class BareSegments:
    """Segments of the run's connection without data or SYN, FIN, RST (the peer's ACKs), found
    between the run's packages: routing them is all they do, so a run goes on over them. Read
    (`columns`) only for `packets.expand`, which gives them back in their places when the run is
    read one by one (rarely: a run its connection cannot take whole)."""

    records: Records
    picks: Any  # the run's packages' records
    others: Any  # these segments' records, in order
    src: bytes  # the run's sender's address

    def columns(self) -> tuple[Any, ...]:
        """How many of the run's packages come before each, its time, whether the run's receiver
        sent it, its sequence and acknowledgment numbers and its flags (numpy columns)."""
        import numpy as np

        records, others = self.records, self.others
        u8, ip, tcp = _tcp_at(np, records, others)
        seq, ack = _word(np, u8, tcp + 4), _word(np, u8, tcp + 8)
        src = np.frombuffer(self.src, dtype=np.uint8)
        reverse = (u8[(ip + 12)[:, None] + np.arange(4)] != src).any(axis=1)
        before = np.searchsorted(self.picks, others)
        return before, records.times[others], reverse, seq, ack, u8[tcp + 13].astype(np.int64)


def _tcp_at(np: Any, records: Records, chosen: Any) -> tuple[Any, Any, Any]:
    """The block's bytes, and where the IP and TCP headers of the records `chosen` start."""
    u8 = np.frombuffer(records.buf, dtype=np.uint8)
    ip, _ = ip_offsets(u8, records.offsets[chosen], records.links[chosen])
    return u8, ip, ip + (u8[ip] & 0x0F).astype(np.int64) * 4


def _word(np: Any, u8: Any, at: Any) -> Any:
    """The big-endian 32-bit numbers at offsets `at`."""
    word = np.array([1 << 24, 1 << 16, 1 << 8, 1], dtype=np.int64)
    return (u8[at[:, None] + np.arange(4)] * word).sum(axis=1)


# a run found in a block: its first record, the one after its last, its packages' records (None:
# every record first..end-1) and the segments without data it goes on over (None: none)
Found = tuple[int, int, Any, Any]


def runs(records: Records, interleaved: bool = True, fixed: frozenset[int] = frozenset()) -> list[Found]:
    """Every run of at least MIN_RUN data frames in order on one connection direction, by first record.

    A run goes on over its connection's segments without data (both sides' ACKs) and, when
    `interleaved`, over whatever cannot change that direction's state: other connections'
    segments, and its own connection's data packages the other way (a control session's
    inputs between its outputs, each in a run of its own or read one by one after this run).
    Anything else of its connection (a control message, SYN, FIN, RST, a package split
    across segments) and any frame not read here as IPv4 and TCP (a fragment may be of it)
    ends it. `interleaved=False`: only its own bare segments come between its packages, so
    a run expanded in its place gives the file's order (`packets.segments`).

    `fixed`: ports of protocols whose records have one size a connection (URCL's external
    control, the real-time interface): segments of one size in a row on such a connection are
    runs too, with only the connection's bare segments between them (any other data of it ends
    the run).
    """
    import numpy as np

    if len(records.offsets) < MIN_RUN:
        return []
    h = _headers(np, records)
    data = np.flatnonzero(h.ok)
    other = np.flatnonzero(_on_ports(np, h, fixed)) if fixed else data[:0]
    if len(data) < MIN_RUN and len(other) < MIN_RUN:
        return []
    ends_a, ends_b = (h.src << 16) | (h.ports >> 16), (h.dst << 16) | (h.ports & 0xFFFF)
    low, high = np.minimum(ends_a, ends_b), np.maximum(ends_a, ends_b)  # the connection
    order, rank, conn = _by_connection(np, low, high, h.tcp4)
    way = (ends_a != low).astype(np.int64) + (0 if conn is None else 2 * conn)  # each record's direction

    def per_connection(flags: Any) -> Any:  # counted in each connection's records in file order
        return np.cumsum(flags if order is None else flags[order])

    found: list[Found] = []
    if len(data) >= MIN_RUN:
        local = h.bare if not interleaved else (h.tcp4 & ~h.ok & ~h.bare) | _out_of_order(np, h, way)
        key = [h.src, h.dst, h.ports, h.size, h.prefix]  # the prefix: size, type, recipe
        mode = "over" if interleaved else "file"
        found += _linked(np, h, data, key, per_connection(local), rank, way, mode)
    if len(other) >= MIN_RUN:
        key = [h.src, h.dst, h.ports, h.size]
        between = "connection" if interleaved else "file"
        found += _linked(np, h, other, key, per_connection(h.bare), rank, way, between)
    found.sort(key=lambda run: run[0])
    return found


def _out_of_order(np: Any, h: _Headers, way: Any) -> Any:
    """Data segments not following the one before them in their direction (a hole, a copy): a
    run of the other direction ends there, since its packages' acknowledgments may give up the
    hole (`runs._peer_waits`). None when one direction alone sends data (its run is in order)."""
    found = np.zeros(len(way), dtype=bool)
    data = np.flatnonzero(h.tcp4 & (h.size > 0))
    ways = way[data]
    if len(data) < 2 or (ways == ways[0]).all():
        return found
    data = data[np.argsort(ways, kind="stable")]  # each direction's data segments in file order
    a, b = data[:-1], data[1:]
    found[b] = (way[a] == way[b]) & (h.seq[b] != (h.seq[a] + h.size[a]) % (1 << 32))
    return found


def _on_ports(np: Any, h: _Headers, ports: frozenset[int]) -> Any:
    """Segments with data that are not data packages, to or from one of `ports`."""
    wanted = np.fromiter(ports, dtype=np.int64, count=len(ports))
    either = np.isin(h.ports >> 16, wanted) | np.isin(h.ports & 0xFFFF, wanted)
    return h.plain & (h.size > 0) & ~h.ok & either


def _linked(
    np: Any, h: _Headers, data: Any, key: list[Any], counted: Any, rank: Any, way: Any, between: str
) -> list[Found]:
    """The runs among the records `data`: grouped by `key`, each following the one before in
    sequence, with nothing between that ends a run. `counted`, per connection (by `rank`): what
    ends a run so far (`between` "over": the run goes over everything else but frames not read
    as TCP), or the bare segments, which are all that may come between of its connection
    ("connection"; nor a frame not read as TCP) or at all ("file")."""
    chain = data[np.lexsort([data, *(column[data] for column in reversed(key))])]
    a, b = chain[:-1], chain[1:]  # the records grouped by key, each group in file order
    follows = h.seq[b] == (h.seq[a] + h.size[a]) % (1 << 32)
    for column in key:
        follows &= column[b] == column[a]
    ra, rb = (a, b) if rank is None else (rank[a], rank[b])
    if between == "file":
        follows &= counted[rb] - counted[ra] == b - a - 1
    else:
        breaks = np.cumsum(~h.tcp4)
        follows &= breaks[b] == breaks[a]
        ends = counted[rb] - counted[ra]
        follows &= (ends == 0) if between == "over" else (ends == rb - ra - 1)
    return _chains(np, chain, follows, h.bare, way)


@dataclass
class _Headers:
    """The IPv4 and TCP headers of a block's records, as numpy columns."""

    tcp4: Any  # a whole IPv4 TCP segment, not a fragment, read here
    plain: Any  # ... without SYN, FIN, RST
    bare: Any  # ... and without data
    ok: Any  # ... exactly one data package
    src: Any
    dst: Any
    ports: Any  # source port << 16 | destination port
    size: Any  # bytes of data
    prefix: Any  # the data's first bytes (a data package's size, type, recipe)
    seq: Any


def _headers(np: Any, records: Records) -> _Headers:
    u8 = np.frombuffer(records.buf, dtype=np.uint8)
    last = len(u8) - 1
    cap_end = records.offsets + records.lengths
    ip, tcp4 = ip_offsets(u8, records.offsets, records.links)

    def at(index: Any) -> Any:
        return u8[np.minimum(index, last)].astype(np.int64)

    def be(index: Any, width: int) -> Any:
        value = at(index)
        for k in range(1, width):
            value = (value << 8) | at(index + k)
        return value

    tcp4 &= cap_end >= ip + IP_MIN + TCP_MIN
    tcp4 &= (at(ip) >> 4) == 4
    tcp4 &= at(ip + 9) == TCP
    tcp4 &= (be(ip + 6, 2) & 0x3FFF) == 0  # not a fragment
    ihl = (at(ip) & 0x0F) * 4
    tcp = ip + ihl
    tcp4 &= (ihl >= IP_MIN) & (tcp + TCP_MIN <= cap_end)
    pay = tcp + (at(tcp + 12) >> 4) * 4
    total = be(ip + 2, 2)
    end = np.where(total == 0, cap_end, ip + total)  # 0: segmentation offload, the frame's length
    size = end - pay
    tcp4 &= (end <= cap_end) & ((at(tcp + 12) >> 4) * 4 >= TCP_MIN)
    plain = tcp4 & ((at(tcp + 13) & NOT_DATA) == 0)
    bare = plain & (size == 0)
    ok = plain & (size > 4) & (at(pay + TYPE_AT) == DATA_PACKAGE_TYPE)
    ok &= be(pay + SIZE_AT, SIZE_BYTES) == size
    src, dst, ports = be(ip + 12, 4), be(ip + 16, 4), be(tcp, 4)
    return _Headers(tcp4, plain, bare, ok, src, dst, ports, size, be(pay, PREFIX_BYTES), be(tcp + 4, 4))


def _by_connection(np: Any, low: Any, high: Any, tcp4: Any) -> tuple[Any, Any, Any]:
    """The records by connection, each connection's in file order; each record's place in that
    order; its connection's number. (None, None, None): the block's segments are all of one
    connection (the common case)."""
    if (low[tcp4] == low[tcp4][0]).all() and (high[tcp4] == high[tcp4][0]).all():
        return None, None, None
    # each end numbered (1-D sorts: unique over pairs of columns sorts them as bytes, 10x slower)
    lows, highs = (np.unique(np.where(tcp4, end, -1), return_inverse=True) for end in (low, high))
    pair = lows[1].reshape(-1).astype(np.int64) * len(highs[0]) + highs[1].reshape(-1)
    conn = np.unique(pair, return_inverse=True)[1].reshape(-1)
    order = np.argsort(conn, kind="stable")
    rank = np.empty(len(conn), dtype=np.int64)
    rank[order] = np.arange(len(conn))
    return order, rank, conn


def _chains(np: Any, chain: Any, follows: Any, bare: Any, way: Any) -> list[Found]:
    """The runs of `chain` (data records grouped by key) where each follows the one before, by
    first record, with the bare segments of their connection between their packages."""
    starts = np.flatnonzero(np.concatenate(([True], ~follows)))
    ends = np.append(starts[1:], len(chain))
    keep = ends - starts >= MIN_RUN
    starts, ends = starts[keep], ends[keep]
    firsts, finals = chain[starts], chain[ends - 1] + 1
    spread = finals - firsts != ends - starts  # other records between its packages
    others = _bare_between(np, np.flatnonzero(bare), way, way[firsts[spread]], firsts[spread], finals[spread])
    found: list[Found] = []
    each = iter(others)
    for first, end, start, stop, apart in zip(
        firsts.tolist(), finals.tolist(), starts.tolist(), ends.tolist(), spread.tolist(), strict=True
    ):
        found.append((first, end, chain[start:stop], next(each)) if apart else (first, end, None, None))
    return found


def _bare_between(np: Any, bare: Any, way: Any, run_way: Any, first: Any, end: Any) -> list[Any]:
    """For each run (its direction, first record, the one after its last), the bare segments
    (records `bare`) of its connection within it, None for none; a segment within runs of both
    directions goes to the one that starts first. Runs of one direction never overlap, so each
    segment has at most one candidate a direction: found by one search per direction."""
    out: list[Any] = [None] * len(first)
    if not len(bare) or not len(first):
        return out
    span = int(max(end.max(), bare.max())) + 1
    order = np.lexsort((first, run_way))
    keys = run_way[order] * span + first[order]  # runs by direction, then first record
    best, best_first = np.full(len(bare), -1), np.full(len(bare), span)
    for flip in (0, 1):  # the segment's own direction, then the other
        direction = way[bare] ^ flip
        at = np.searchsorted(keys, direction * span + bare) - 1  # the last run starting before it
        run = order[np.maximum(at, 0)]
        hit = (at >= 0) & (run_way[run] == direction) & (end[run] > bare) & (first[run] < best_first)
        best[hit], best_first[hit] = run[hit], first[run][hit]
    chosen = best >= 0
    owner, segments = best[chosen], bare[chosen]
    by_run = np.argsort(owner, kind="stable")
    owner, segments = owner[by_run], segments[by_run]
    bounds = np.searchsorted(owner, np.arange(len(first) + 1)).tolist()
    for n in range(len(first)):
        if bounds[n + 1] > bounds[n]:
            out[n] = segments[bounds[n] : bounds[n + 1]]
    return out


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


def run_of(records: Records, first: int, end: int, picks: Any = None, others: Any = None) -> DataRun:
    """The DataRun of records first..end-1 (as `runs` found them; `picks`: its packages' records
    where other records come between them, `others`: its connection's segments without data
    among those)."""
    import numpy as np

    buf = records.buf
    u8 = np.frombuffer(buf, dtype=np.uint8)  # header lengths may differ frame to frame (options)
    chosen = slice(first, end) if picks is None else picks
    ips, _ = ip_offsets(u8, records.offsets[chosen], records.links[chosen])
    ip = int(ips[0])
    tcp = ip + (buf[ip] & 0x0F) * 4
    pay = tcp + (buf[tcp + 12] >> 4) * 4
    total = int.from_bytes(buf[ip + 2 : ip + 4], "big")  # 0: segmentation offload, the frame's length
    at = first if picks is None else int(picks[0])
    size = (ip + total if total else int(records.offsets[at] + records.lengths[at])) - pay  # its data
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
        None if others is None else BareSegments(records, picks, others, bytes(buf[ip + 12 : ip + 16])),
        (records, chosen),
    )
