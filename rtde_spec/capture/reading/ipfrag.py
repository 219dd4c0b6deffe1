"""IPv4 fragments put back together (RFC 791), in bounded memory: a segment split by a router
or by a big send on a small MTU is decoded whole, not counted as bytes never captured."""

from __future__ import annotations

from collections import OrderedDict

MAX_DATAGRAMS = 1024  # datagrams waiting for their other fragments; the oldest is dropped past this
ETHERNET_IPV4 = b"\0" * 12 + b"\x08\x00"  # the link header a reassembled datagram is given


class Fragments:
    """Fragments by (source, destination, protocol, id); `add` returns the whole datagram once complete."""

    def __init__(self, counts: dict[str, int]) -> None:
        self.counts = counts
        self.pending: OrderedDict[bytes, dict[int, bytes]] = OrderedDict()
        self.heads: dict[bytes, bytes] = {}  # the first fragment's IP header
        self.ends: dict[bytes, int] = {}  # the datagram's payload size, from its last fragment

    def add(self, frame: bytes, at: int) -> bytes | None:
        """One fragment of the IPv4 datagram at `frame[at:]`; an Ethernet frame of it when complete."""
        counts = self.counts
        counts["ip_fragments"] = counts.get("ip_fragments", 0) + 1
        header = (frame[at] & 0x0F) * 4
        total = int.from_bytes(frame[at + 2 : at + 4], "big")
        flags = int.from_bytes(frame[at + 6 : at + 8], "big")
        offset, more = (flags & 0x1FFF) * 8, bool(flags & 0x2000)
        key = frame[at + 12 : at + 20] + frame[at + 9 : at + 10] + frame[at + 4 : at + 6]
        pieces = self.pending.get(key)
        if pieces is None:
            pieces = self.pending[key] = {}
            if len(self.pending) > MAX_DATAGRAMS:
                old, lost = self.pending.popitem(last=False)
                self.heads.pop(old, None)
                self.ends.pop(old, None)
                counts["ip_fragments_dropped"] = counts.get("ip_fragments_dropped", 0) + 1
                counts["ip_fragments_lost"] = counts.get("ip_fragments_lost", 0) + len(lost)
        pieces[offset] = frame[at + header : at + total]
        if offset == 0:
            self.heads[key] = frame[at : at + header]
        if not more:
            self.ends[key] = offset + total - header
        whole = self._whole(key)
        if whole is None:
            return None
        counts["ip_reassembled"] = counts.get("ip_reassembled", 0) + 1
        head = bytearray(self.heads.pop(key))
        del self.pending[key], self.ends[key]
        head[2:4] = (len(head) + len(whole)).to_bytes(2, "big")
        head[6:8] = b"\0\0"
        return ETHERNET_IPV4 + bytes(head) + whole

    def finish(self) -> None:
        """The end of the capture: fragments of datagrams never completed are counted as lost."""
        waiting = sum(len(pieces) for pieces in self.pending.values())
        if waiting:
            self.counts["ip_fragments_lost"] = self.counts.get("ip_fragments_lost", 0) + waiting
        self.pending.clear()
        self.heads.clear()
        self.ends.clear()

    def _whole(self, key: bytes) -> bytes | None:
        end = self.ends.get(key)
        if end is None or key not in self.heads:
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
