"""TCP segments out of pcap and pcapng files, headers read with `struct`.

Link types: Ethernet (with 802.1Q/802.1ad tags), Linux cooked (SLL and SLL2), BSD
loopback/null, raw IP, Linux NFLOG, and Apple's PKTAP around any of them; IPv4 and IPv6
(hop-by-hop, routing and destination options skipped), fragments of either put back together
(`ipfrag.py`); tunnels unwrapped (GRE, ERSPAN, VXLAN, Geneve, IP in IP, MPLS: `tunnels.py`).
Anything else is counted, not decoded: other protocols as `not_tcp`; frames that claim IP but
whose headers cannot be read as `undecodable` (per reason, with the first frame's number), and
link types not read here as `unknown_link` (both reported as damage by the summary).
"""

from __future__ import annotations

import socket
import struct
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import NamedTuple

from rtde_spec.capture.reading import tunnels
from rtde_spec.capture.reading.bulk import ACK, DataRun, Found, run_of, runs
from rtde_spec.capture.reading.compressed import open_capture
from rtde_spec.capture.reading.ipfrag import Addresses
from rtde_spec.capture.reading.link_types import COOKED, ETHERNET, LINK_HEADERS, LOOPBACK, RAW_IP
from rtde_spec.capture.reading.pcapfile import blocks

FIN, SYN, RST = 0x01, 0x02, 0x04
ACK_PSH = 0x18  # the flags a run's segments stand for (a run has no FIN, SYN or RST)
IPV4, IPV6 = 0x0800, 0x86DD
TCP = 6
IPV6_OPTION_HEADERS = {0, 43, 60}  # hop-by-hop, routing, destination options: skipped over
IPV6_FRAGMENT = 44
MAY_HOLD_TCP = frozenset({TCP, *IPV6_OPTION_HEADERS, *tunnels.CARRIERS})  # what fragments are put together
_TCP = struct.Struct(">HHIIBB")  # ports, seq, ack, data offset byte, flags


class Segment(NamedTuple):
    time: float
    src: str
    sport: int
    dst: str
    dport: int
    seq: int
    flags: int
    payload: bytes
    ack: int = -1  # the acknowledgment number, when the ACK flag is set (-1: none, or not read)


class Inner(NamedTuple):
    """Where to read on: a tunnel's packet inside a frame, or a datagram put back together."""

    frame: bytes
    kind: int  # ethertype-like: IPv4, IPv6, MPLS
    at: int


class UnknownLink(Exception):
    """A frame of a link type this reader does not decode (or of an interface the file never described)."""


PKTAP = 258  # Apple's per-packet metadata, then the frame of the link type it names
NFLOG = 239  # Linux netfilter's log (`tcpdump -i nflog:N`)
MAX_DEPTH = 8  # IP headers read in one frame: tunnels in tunnels, fragments put back together
WHY, FIRST, MAX_REASONS = "why:", "first:", 16  # unreadable frames per reason (`_unreadable`)


def _ip_start(linktype: int, frame: bytes) -> tuple[int, int]:
    """(ethertype-like IP version tag, offset of the IP header) of a frame.

    Raises UnknownLink for a link type not read here, ValueError for a frame shorter than its
    link header (unreadable, not "not TCP")."""
    if len(frame) < LINK_HEADERS.get(linktype, 0):
        raise ValueError("shorter than its link header")
    if linktype == ETHERNET:
        return tunnels.ethernet(frame, 0)
    if linktype in COOKED:  # Linux cooked v1 and v2
        at, ip = COOKED[linktype]
        return int.from_bytes(frame[at : at + 2], "big"), ip
    if linktype in LOOPBACK:
        return (IPV4 if len(frame) > 4 and frame[4] >> 4 == 4 else IPV6), 4
    if linktype in RAW_IP:
        return (IPV4 if frame and frame[0] >> 4 == 4 else IPV6), 0
    if linktype == PKTAP:
        return _pktap(frame)
    if linktype == NFLOG:
        return tunnels.nflog(frame)
    raise UnknownLink(linktype)


def _pktap(frame: bytes) -> tuple[int, int]:
    """Apple's PKTAP (a capture through macOS's pktap interface that keeps its headers): a header
    in the host's (little-endian) order naming its own length, whether a packet follows (1) and
    that packet's link type."""
    if len(frame) < 12:
        raise ValueError("shorter than its PKTAP header")
    length, follows, inner = struct.unpack_from("<III", frame)
    if follows != 1:  # no packet after the header (a drop report): nothing of TCP
        return 0, 0
    if not 12 <= length <= len(frame) or inner == PKTAP:
        raise ValueError("a PKTAP header that cannot be one")
    kind, at = _ip_start(inner, frame[length:])
    return kind, length + at


def _tcp_of(linktype: int, frame: bytes, book: Addresses) -> tuple[str, str, int, int, bytes] | None:
    """(src, dst, TCP header offset, end of the TCP segment, the frame they are in); None when the
    frame is not TCP (another protocol), or a fragment of a datagram not yet whole.

    A frame that claims IP (by its link header) but whose IP or TCP header cannot be one raises
    ValueError: it is counted as unreadable, never passed over as "not TCP". An IPv4 total length
    of 0 (or an IPv6 payload length of 0) is a segment that TCP segmentation offload had not cut
    yet when the sending host captured it: its length is the frame's, as Wireshark takes it.
    A tunnel's packet (`tunnels.py`) is read on inside the same frame, at most MAX_DEPTH deep."""
    kind, at = _ip_start(linktype, frame)
    for depth in range(MAX_DEPTH):
        if kind in tunnels.MPLS:
            start = tunnels.mpls(frame, at, len(frame))
            if start is None:
                return None
            kind, at = start
            continue
        found = _ip(kind, frame, at, book, depth > 0)
        if not isinstance(found, Inner):
            return found
        frame, kind, at = found
    raise ValueError(f"tunnels nested more than {MAX_DEPTH} deep")


def _ip(
    kind: int, frame: bytes, at: int, book: Addresses, inner: bool = False
) -> tuple[str, str, int, int, bytes] | Inner | None:
    """The TCP segment of the IP packet at frame[at:]; or, for a tunnel or a datagram just put back
    together, the frame and where in it to read on. `inner`: a packet a tunnel carried, which may
    have been cut (a mirror session's MTU, ERSPAN's T bit) where no capture record says so."""
    if kind == IPV4:
        if len(frame) < at + 20 or frame[at] >> 4 != 4 or frame[at] & 0x0F < 5:
            raise ValueError("no IPv4 header")
        protocol = frame[at + 9]
        if protocol != TCP and protocol not in tunnels.CARRIERS:
            return None
        if int.from_bytes(frame[at + 6 : at + 8], "big") & 0x3FFF:  # more fragments, or an offset
            whole = book.fragments.add(frame, at)
            return None if whole is None else Inner(whole, IPV4, 14)
        total = int.from_bytes(frame[at + 2 : at + 4], "big")
        tcp = at + (frame[at] & 0x0F) * 4
        if total == 0:  # segmentation offload: the frame's length
            end = len(frame)
        elif at + total < tcp:
            raise ValueError("IPv4 total length shorter than its header")
        else:
            end = min(len(frame), at + total)  # not the padding
            if inner and end < at + total:
                _cut_in_tunnel(book)
        src, dst, family = frame[at + 12 : at + 16], frame[at + 16 : at + 20], socket.AF_INET
    elif kind == IPV6:
        if len(frame) < at + 40 or frame[at] >> 4 != 6:
            raise ValueError("no IPv6 header")
        payload = int.from_bytes(frame[at + 4 : at + 6], "big")
        if payload == 0 and frame[at + 6] != 59:  # a jumbogram or an offloaded segment (59: nothing next)
            end = len(frame)
        else:
            end = min(len(frame), at + 40 + payload)
            if inner and end < at + 40 + payload:
                _cut_in_tunnel(book)
        src, dst, family = frame[at + 8 : at + 24], frame[at + 24 : at + 40], socket.AF_INET6
        protocol, tcp = frame[at + 6], at + 40
        while protocol in IPV6_OPTION_HEADERS or (protocol == IPV6_FRAGMENT and _atomic(frame, tcp, end)):
            if tcp + 2 > end:
                raise ValueError("IPv6 extension headers beyond the packet")
            size = 8 if protocol == IPV6_FRAGMENT else (frame[tcp + 1] + 1) * 8
            protocol, tcp = frame[tcp], tcp + size
        if protocol == IPV6_FRAGMENT:
            if tcp + 8 > end or payload == 0:
                raise ValueError("an IPv6 fragment header beyond the packet")
            if frame[tcp] not in MAY_HOLD_TCP:  # ICMPv6 and the like: not TCP, as IPv4's are not
                return None
            whole = book.fragments.add_v6(frame, at, tcp)
            return None if whole is None else Inner(whole, IPV6, 14)
        if protocol != TCP and protocol not in tunnels.CARRIERS:
            return None
    else:
        return None
    if protocol != TCP:
        start = tunnels.inner(protocol, frame, tcp, end)
        return None if start is None else Inner(frame[:end], *start)
    if tcp + 20 > end or frame[tcp + 12] >> 4 < 5:
        raise ValueError("no whole TCP header")
    return _name(book, src, family), _name(book, dst, family), tcp, end, frame


def _name(book: Addresses, raw: bytes, family: int) -> str:
    """An address as text, converted once (a bounded cache: a scan's million sources reuse none)."""
    names = book.names
    if raw not in names:
        if len(names) >= book.MAX:
            names.clear()
        names[raw] = socket.inet_ntop(family, raw)
    return names[raw]


def _cut_in_tunnel(book: Addresses) -> None:
    """A packet in a tunnel shorter than its IP length: counted, so the summary names the cause of
    the gaps it leaves, as it names a snap length."""
    counts = book.fragments.counts
    counts["tunnel_cut"] = counts.get("tunnel_cut", 0) + 1


def _atomic(frame: bytes, at: int, end: int) -> bool:
    """Whether the IPv6 fragment header at `at` is an atomic fragment (RFC 6946: offset 0, no more
    fragments): the whole packet, its fragment header to be skipped like an option header."""
    return at + 8 <= end and not int.from_bytes(frame[at + 2 : at + 4], "big") & 0xFFF9


def _segment(
    ts: float, linktype: int, frame: bytes, book: Addresses, counts: dict[str, int], number: int = 0
) -> Segment | None:
    """The TCP segment in one frame (`number`: its number in the file, from 1); None (counted) when
    it is not one, or cannot be read."""
    fragments = counts.get("ip_fragments", 0)
    book.fragments.now = ts  # fragments held past their time-out expire by capture time
    try:
        found = _tcp_of(linktype, frame, book)
    except UnknownLink:
        counts["unknown_link"] = counts.get("unknown_link", 0) + 1
        counts["unknown_link_type"] = linktype
        return None
    except (IndexError, ValueError, OSError) as e:
        _unreadable(counts, str(e) if isinstance(e, ValueError) else "a header cut short", number)
        return None
    if found is None:
        if counts.get("ip_fragments", 0) == fragments:  # a fragment waiting for the rest is not "not TCP"
            counts["not_tcp"] = counts.get("not_tcp", 0) + 1
        return None
    src, dst, at, end, frame = found
    sport, dport, seq, ack, offset, flags = _TCP.unpack_from(frame, at)
    data = at + (offset >> 4) * 4
    if data > end:
        _unreadable(counts, "a TCP header longer than its segment", number)
        return None
    return Segment(ts, src, sport, dst, dport, seq, flags, frame[data:end], ack if flags & ACK else -1)


def _unreadable(counts: dict[str, int], why: str, number: int) -> None:
    """A frame whose headers cannot be read: counted, and per reason how many and the number of
    the first (`why:REASON`, `first:REASON`), so the summary says what and where (Wireshark's
    frame numbers). At most MAX_REASONS reasons are kept apart; the rest count in the total."""
    counts["undecodable"] = counts.get("undecodable", 0) + 1
    key = WHY + why
    if key not in counts and sum(k.startswith(WHY) for k in counts) >= MAX_REASONS:
        return
    counts[key] = counts.get(key, 0) + 1
    if number:
        counts.setdefault(FIRST + why, number)


def items(
    path: str | Path | Sequence[str | Path],
    stats: dict[str, int] | None = None,
    progress: Callable[[int], None] | None = None,
    lag: int = 0,
    interleaved: bool = True,
    fixed: frozenset[int] = frozenset(),
) -> Iterator[Segment | DataRun]:
    """TCP segments of a capture in file order; runs of data segments as one DataRun each.

    Runs are found per block of the file among Ethernet frames (`capture/reading/bulk.py`); every
    other frame comes segment by segment. `lag`: blocks kept mapped after they are handed
    on, for runs decoded later on other threads (`pcapfile.blocks`). A list of paths is the
    parts of one split capture (`series.py`), read one after the other as one capture.
    A run comes where its first package is: `interleaved`, it may span frames of other
    connections and of its own the other way, which come after it (`bulk.runs`). `fixed`:
    ports whose records are of one size (URCL's external control, the real-time interface),
    found in runs too.
    """
    counts = stats if stats is not None else {}
    counts.setdefault("frames", 0)
    book = Addresses(counts)  # raw address -> text, converted once per address; IPv4 fragments
    parts = [path] if isinstance(path, (str, Path)) else list(path)
    before = 0  # bytes of the parts read already (progress counts the whole series)
    for part in parts:
        reached = 0
        with open_capture(part, counts) as f:
            for records in blocks(f, str(part), counts, lag):
                buf = records.buf
                offsets, lengths = records.offsets.tolist(), records.lengths.tolist()
                times, links = records.times.tolist(), records.links.tolist()
                number = counts["frames"] + 1  # of the block's first frame
                counts["frames"] += len(offsets)
                found = runs(records, interleaved, fixed)
                alone = _read_alone(found, len(offsets))
                i = 0
                for first, end, picks, others in [*found, (len(offsets), 0, None, None)]:
                    while i < len(alone) and alone[i] < first:
                        k = alone[i]
                        i += 1
                        frame = buf[offsets[k] : offsets[k] + lengths[k]]
                        seg = _segment(times[k], links[k], frame, book, counts, number + k)
                        if seg is not None:
                            yield seg
                    if first < end:
                        yield run_of(records, first, end, picks, others)
                reached = records.upto
                if progress is not None:
                    progress(before + reached)
        before += reached
    book.fragments.finish()


def segments(
    path: str | Path, stats: dict[str, int] | None = None, progress: Callable[[int], None] | None = None
) -> Iterator[Segment]:
    """Every TCP segment of a capture file, in file order (runs expanded)."""
    for item in items(path, stats, progress, interleaved=False):
        if isinstance(item, Segment):
            yield item
        else:
            yield from expand(item)


def _read_alone(found: list[Found], count: int) -> list[int]:
    """The records of a block no run stands for, in order."""
    if not found:
        return list(range(count))
    import numpy as np

    taken = np.zeros(count, dtype=bool)
    for first, end, picks, others in found:
        if picks is None:
            taken[first:end] = True
        else:
            taken[picks] = True
            if others is not None:
                taken[others] = True
    return np.flatnonzero(~taken).tolist()


def first_of(run: DataRun) -> Segment:
    """The first segment of a DataRun (its first package: what comes without data is after it)."""
    row = run.rows[0].tobytes()
    return Segment(float(run.times[0]), run.src, run.sport, run.dst, run.dport, run.seq, ACK_PSH, row)


def expand(run: DataRun) -> Iterator[Segment]:
    """The segments a DataRun stands for, with those without data between them in their places."""
    bare = run.bare
    waiting = [] if bare is None else list(zip(*(c.tolist() for c in bare.columns()), strict=True))
    waiting.reverse()  # the first last: popped in order
    ends = ((run.src, run.sport, run.dst, run.dport), (run.dst, run.dport, run.src, run.sport))
    acks = run.acks() or [-1] * len(run.times)
    for i, (ts, row) in enumerate(zip(run.times.tolist(), run.rows, strict=True)):
        while waiting and waiting[-1][0] <= i:
            _, when, back, seq, ack, flags = waiting.pop()
            yield Segment(when, *ends[back], seq, flags, b"", ack if flags & ACK else -1)
        seq = (run.seq + i * run.size) % (1 << 32)
        yield Segment(ts, *ends[0], seq, ACK_PSH, row.tobytes(), acks[i])
