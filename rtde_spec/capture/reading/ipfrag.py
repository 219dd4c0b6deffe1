"""IPv4 fragments put back together (RFC 791), in bounded memory: a segment split by a router
or by a big send on a small MTU is decoded whole, not counted as bytes never captured."""

from __future__ import annotations

from bisect import bisect_left
from collections import OrderedDict

MAX_DATAGRAMS = 1024  # datagrams waiting for their other fragments; the oldest is dropped past this
MAX_DONE_BYTES = 1 << 22  # payloads of datagrams just put together, kept to know copies of their fragments
ETHERNET_IPV4 = b"\0" * 12 + b"\x08\x00"  # the link header a reassembled datagram is given


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

    def add(self, frame: bytes, at: int) -> bytes | None:
        """One fragment of the IPv4 datagram at `frame[at:]`; an Ethernet frame of it when complete."""
        counts = self.counts
        counts["ip_fragments"] = counts.get("ip_fragments", 0) + 1
        header = (frame[at] & 0x0F) * 4
        total = int.from_bytes(frame[at + 2 : at + 4], "big")
        flags = int.from_bytes(frame[at + 6 : at + 8], "big")
        offset, more = (flags & 0x1FFF) * 8, bool(flags & 0x2000)
        key = frame[at + 12 : at + 20] + frame[at + 9 : at + 10] + frame[at + 4 : at + 6]
        if (
            key in self.done
            and key not in self.pending
            and self._copy(key, offset, frame[at + header : at + total])
        ):
            return None
        pieces = self.pending.get(key)
        if pieces is None:
            pieces = self.pending[key] = {}
            if len(self.pending) > MAX_DATAGRAMS:
                old, lost = self.pending.popitem(last=False)
                self.heads.pop(old, None)
                self.ends.pop(old, None)
                self.reach.pop(old, None)
                counts["ip_fragments_dropped"] = counts.get("ip_fragments_dropped", 0) + 1
                counts["ip_fragments_lost"] = counts.get("ip_fragments_lost", 0) + len(lost)
        before = pieces.get(offset)
        pieces[offset] = frame[at + header : at + total]  # a copy of one held replaces it
        self._place(key, offset, len(pieces[offset]), before)
        if offset == 0:
            self.heads[key] = frame[at : at + header]
        if not more:
            self.ends[key] = offset + total - header
        whole = self._whole(key)
        if whole is None:
            return None
        counts["ip_reassembled"] = counts.get("ip_reassembled", 0) + 1
        head = bytearray(self.heads.pop(key))
        del self.pending[key], self.ends[key], self.reach[key]
        head[2:4] = (len(head) + len(whole)).to_bytes(2, "big")
        head[6:8] = b"\0\0"
        self._keep_done(key, whole)
        return ETHERNET_IPV4 + bytes(head) + whole

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
        waiting = sum(len(pieces) for pieces in self.pending.values())
        if waiting:
            self.counts["ip_fragments_lost"] = self.counts.get("ip_fragments_lost", 0) + waiting
        self.pending.clear()
        self.heads.clear()
        self.ends.clear()
        self.reach.clear()
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
