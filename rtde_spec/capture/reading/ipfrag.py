"""IP fragments put back together (IPv4: RFC 791; IPv6: RFC 8200 section 4.5), in bounded memory:
a segment split by a router or by a big send on a small MTU, or a tunnel's packet grown past the
MTU by its outer headers (ERSPAN of full-size frames), is decoded whole, not counted as bytes
never captured. Both versions share one table, its limits and its rules for copies and overlaps."""

from __future__ import annotations

from bisect import bisect_left
from collections import OrderedDict

MAX_DATAGRAMS = 1024  # datagrams waiting for their other fragments; the oldest is dropped past this
MAX_DONE_BYTES = 1 << 22  # payloads of datagrams just put together, kept to know copies of their fragments
ETHERNET_IPV4 = b"\0" * 12 + b"\x08\x00"  # the link header a reassembled datagram is given
ETHERNET_IPV6 = b"\0" * 12 + b"\x86\xdd"
UDP = 17
TIMEOUT_V4, TIMEOUT_V6 = 30.0, 60.0  # seconds a datagram's fragments are held: Linux's ipfrag_time and
# ip6frag_time, RFC 8200 section 4.5's 60 s; a datagram past them is dropped as the receiver drops it


class Fragments:
    """Fragments by (source, destination, protocol, id); `add` returns the whole datagram once complete."""

    def __init__(self, counts: dict[str, int]) -> None:
        self.counts = counts
        self.pending: OrderedDict[bytes, dict[int, bytes]] = OrderedDict()
        self.heads: dict[bytes, bytes] = {}  # the first fragment's IP header
        self.ends: dict[bytes, int] = {}  # the datagram's payload size, from its last fragment
        self.reach: dict[bytes, tuple[int, int, list[int]]] = {}  # (bytes whole from 0, offsets
        # taken into that, every offset sorted): the fragments are looked at once each, not all
        # again per fragment (8,000 fragments of one datagram took 9.5 s)
        self.done: OrderedDict[bytes, bytes] = OrderedDict()  # key -> payload, the newest last
        self.done_bytes = 0
        self.now = 0.0  # the capture time of the fragment being added (set by the reader)
        self.started: dict[bytes, float] = {}  # when each pending datagram's first fragment came

    def add(self, frame: bytes, at: int) -> bytes | None:
        """One fragment of the IPv4 datagram at `frame[at:]`; an Ethernet frame of it when complete."""
        counts = self.counts
        counts["ip_fragments"] = counts.get("ip_fragments", 0) + 1
        header = (frame[at] & 0x0F) * 4
        total = int.from_bytes(frame[at + 2 : at + 4], "big")
        flags = int.from_bytes(frame[at + 6 : at + 8], "big")
        offset, more = (flags & 0x1FFF) * 8, bool(flags & 0x2000)
        key = frame[at + 12 : at + 20] + frame[at + 9 : at + 10] + frame[at + 4 : at + 6]
        piece = frame[at + header : at + total]
        return self._add(key, offset, more, piece, frame[at : at + header], total - header)

    def add_v6(self, frame: bytes, at: int, fragment: int) -> bytes | None:
        """One fragment of the IPv6 packet at `frame[at:]` whose fragment header is at `fragment`;
        an Ethernet frame of it when complete. RFC 8200 section 4.5: fragments are of one packet by
        source, destination and identification; the offset (13 bits) counts 8-byte units and the M
        flag says more follow. The packet put back together is its IPv6 header with the fragment
        header's Next Header, then the fragmentable part (headers before the fragment header, of
        no use to find TCP, are left out)."""
        self.counts["ip_fragments"] = self.counts.get("ip_fragments", 0) + 1
        word = int.from_bytes(frame[fragment + 2 : fragment + 4], "big")
        key = frame[at + 8 : at + 40] + frame[fragment + 4 : fragment + 8]
        head = bytearray(frame[at : at + 40])
        head[6] = frame[fragment]
        end = at + 40 + int.from_bytes(frame[at + 4 : at + 6], "big")  # as the header says
        piece = frame[fragment + 8 : end]
        return self._add(key, word & 0xFFF8, bool(word & 1), piece, bytes(head), end - fragment - 8)

    def _add(self, key: bytes, offset: int, more: bool, piece: bytes, head: bytes, size: int) -> bytes | None:
        """One fragment (`piece` at `offset` of its datagram, `size` bytes as its header says: a
        snap length may have cut the piece shorter); `head`: the IP header its datagram is given
        when whole (the first fragment's)."""
        counts = self.counts
        if key in self.done and key not in self.pending and self._copy(key, offset, piece):
            return None
        self._expire()
        pieces = self.pending.get(key)
        if pieces is None:
            pieces = self.pending[key] = {}
            self.started[key] = self.now
            if len(self.pending) > MAX_DATAGRAMS:
                self._drop("ip_fragments_dropped")
        before = pieces.get(offset)
        pieces[offset] = piece  # a copy of one held replaces it
        self._place(key, offset, len(piece), before)
        if offset == 0:
            self.heads[key] = head
        if not more:
            self.ends[key] = offset + size
        whole = self._whole(key)
        if whole is None:
            return None
        counts["ip_reassembled"] = counts.get("ip_reassembled", 0) + 1
        made = bytearray(self.heads.pop(key))
        del self.pending[key], self.ends[key], self.reach[key], self.started[key]
        self._keep_done(key, whole)
        v6 = made[0] >> 4 == 6
        size = len(whole) + (0 if v6 else len(made))
        at = 4 if v6 else 2  # a length past 16 bits is written 0: the frame's length, as for offload
        made[at : at + 2] = (size if size <= 0xFFFF else 0).to_bytes(2, "big")
        if v6:
            return ETHERNET_IPV6 + bytes(made) + whole
        made[6:8] = b"\0\0"
        return ETHERNET_IPV4 + bytes(made) + whole

    def _expire(self) -> None:
        """Datagrams held past their time-out, oldest first (the table is in the order they began;
        a capture clock stepped back expires nothing until it passes them again)."""
        while self.pending:
            key = next(iter(self.pending))
            if self.now - self.started[key] <= (TIMEOUT_V4 if len(key) == 11 else TIMEOUT_V6):
                return
            self._drop("ip_fragments_expired")

    def _drop(self, why: str) -> None:
        """The oldest datagram waiting, its fragments counted as lost and under `why`."""
        old, lost = self.pending.popitem(last=False)
        self._lost(old, len(lost))
        for held in (self.heads, self.ends, self.reach, self.started):
            held.pop(old, None)
        self.counts[why] = self.counts.get(why, 0) + 1

    def _lost(self, key: bytes, fragments: int) -> None:
        """Fragments of a datagram never completed: lost (damage), or, for UDP, `_udp` (no damage
        of their own: UDP carries TCP only in a tunnel, whose inner connection reports its gap;
        other UDP, fragmented and lost, is nothing the tables lose)."""
        head = self.heads.get(key)
        udp = key[8] == UDP if len(key) == 11 else head is not None and head[6] == UDP
        name = "ip_fragments_lost_udp" if udp else "ip_fragments_lost"
        self.counts[name] = self.counts.get(name, 0) + fragments

    def _copy(self, key: bytes, offset: int, piece: bytes) -> bool:
        """Whether a fragment is a copy of one of a datagram just put together (the same frame from a
        second interface or capture point; counted, not a new datagram whose other fragments never
        come); a fragment that differs starts a new datagram of that id."""
        whole = self.done.pop(key)
        self.done_bytes -= len(whole)
        if whole[offset : offset + len(piece)] != piece:
            return False
        self.counts["ip_fragment_copies"] = self.counts.get("ip_fragment_copies", 0) + 1
        self._keep_done(key, whole)
        return True

    def _keep_done(self, key: bytes, whole: bytes) -> None:
        self.done[key] = whole
        self.done_bytes += len(whole)
        while self.done_bytes > MAX_DONE_BYTES:
            self.done_bytes -= len(self.done.popitem(last=False)[1])

    def finish(self) -> None:
        """The end of the capture: fragments of datagrams never completed are counted as lost."""
        for key, pieces in self.pending.items():
            self._lost(key, len(pieces))
        self.pending.clear()
        self.heads.clear()
        self.ends.clear()
        self.reach.clear()
        self.started.clear()
        self.done.clear()
        self.done_bytes = 0

    def _place(self, key: bytes, offset: int, length: int, before: bytes | None) -> None:
        """A fragment's offset among the datagram's, sorted; one before the offsets taken already
        starts within the bytes reached, and is taken at once. A shorter copy of one taken makes
        the bytes reached counted again."""
        reach, taken, offsets = self.reach.get(key, (0, 0, []))
        at = bisect_left(offsets, offset)
        if before is None:
            offsets.insert(at, offset)
            taken += at < taken
        elif at < taken and length < len(before):
            reach = taken = 0
        if at < taken:
            reach = max(reach, offset + length)
        self.reach[key] = (reach, taken, offsets)

    def _reached(self, key: bytes) -> int:
        """How many bytes from 0 the fragments held cover without a hole (each offset taken once)."""
        reach, taken, offsets = self.reach[key]
        pieces = self.pending[key]
        while taken < len(offsets) and offsets[taken] <= reach:
            reach = max(reach, offsets[taken] + len(pieces[offsets[taken]]))
            taken += 1
        self.reach[key] = (reach, taken, offsets)
        return reach

    def _whole(self, key: bytes) -> bytes | None:
        end = self.ends.get(key)
        if end is None or key not in self.heads or self._reached(key) < end:
            return None
        pieces, parts, at = self.pending[key], [], 0
        for offset in sorted(pieces):
            if offset > at:
                return None  # a hole: a fragment still to come
            piece = pieces[offset]
            if offset + len(piece) > at:
                parts.append(piece[at - offset :])
                at = offset + len(piece)
        return b"".join(parts) if at >= end else None


class Addresses:
    """Raw addresses as text, converted once each; bounded (a scan's million sources reuse nothing)."""

    MAX = 1 << 16

    def __init__(self, counts: dict[str, int]) -> None:
        self.names: dict[bytes, str] = {}
        self.fragments = Fragments(counts)
