"""TCP streams: reassembly of one direction of one connection (the layer after packets).

In order: data is delivered at once. Retransmitted and overlapping segments deliver
only the bytes not seen yet; where they overlap bytes seen recently (the last
`RECENT` delivered, or a segment waiting at the same place) with other bytes, the
difference is counted as a conflict (the first copy is kept); a keep-alive probe (one byte
before the next expected, its content any byte: Windows and BSD send a zero) is not
compared, as Wireshark calls it "TCP Keep-Alive". Out-of-order segments
wait behind the hole before them for its retransmission, which a sender makes within
its retransmission time-out (200 ms and up). When the hole has waited HOLE_SECONDS of
capture time, or more than MAX_WAITING bytes wait, it is declared lost: it is counted
as a gap of so many bytes and delivery resumes after it; the framing above then looks
for the next package. At the end of the capture every hole still open is declared
lost (`drain`), so data after any number of holes is delivered.

Every segment costs O(log n) in the segments waiting (a heap of their places, a queue
of their arrival times), whatever the pattern of holes: sequence numbers are unwrapped
to absolute stream positions, so ordering never scans. This module knows nothing of
the protocols.
"""

from __future__ import annotations

import heapq
from collections import deque
from dataclasses import dataclass, field

MOD = 1 << 32
HALF = MOD // 2
MAX_WAITING = 1 << 20  # bytes held behind a hole before it is declared lost: bounds memory
HOLE_SECONDS = 2.0  # capture seconds a hole waits for its retransmission (TCP's RTO is 0.2 s to ~1 s)
RECENT = 16 << 10  # delivered bytes kept to compare retransmissions with


@dataclass
class Chunk:
    time: float
    data: bytes
    gap_before: int = 0  # bytes lost just before this chunk (a hole declared lost)
    midstream: bool = False  # the first chunk of a stream whose start (SYN) is not in the capture


@dataclass
class Direction:
    base: int | None = None  # the sequence number of stream position 0
    pos: int = 0  # stream position of the next byte expected (sequence numbers unwrapped)
    waiting: dict[int, tuple[float, bytes]] = field(default_factory=dict)  # position -> (time, bytes)
    waiting_bytes: int = 0
    gaps: int = 0
    lost_bytes: int = 0
    conflicts: int = 0  # retransmissions whose bytes differ from the copy kept
    conflict_bytes: int = 0
    copies: int = 0  # segments (a SYN too) wholly seen before: retransmissions, or a second capture point
    midstream: bool = False  # no SYN seen: the next chunk delivered is the first, from mid-stream
    _starts: list[int] = field(default_factory=list)  # heap of waiting positions
    _arrivals: deque[tuple[float, int]] = field(default_factory=deque)  # (time, position), oldest first
    _recent: bytearray = field(default_factory=bytearray)  # the last delivered bytes, ending at `pos`

    @property
    def next_seq(self) -> int | None:
        return None if self.base is None else (self.base + self.pos) % MOD

    def _at(self, seq: int) -> int:
        """The stream position of sequence number `seq` (the nearest one to where the stream is)."""
        assert self.base is not None
        rel = (seq - self.base - self.pos) % MOD
        return self.pos + (rel - MOD if rel >= HALF else rel)

    def feed(self, time: float, seq: int, payload: bytes, syn: bool = False) -> list[Chunk]:
        if syn:
            # the SYN already seen, again (retransmitted, or the same frame from a second interface or
            # capture point), is no new start: restarting would decode what followed it twice
            if self.base != (seq + 1) % MOD:
                self.base, self.pos = (seq + 1) % MOD, 0
            else:
                self.copies += 1
            seq = (seq + 1) % MOD  # data in a SYN (TCP Fast Open, RFC 7413) is the stream's first
        if not payload:
            return []
        if self.base is None:  # a capture that starts mid-stream
            self.base, self.pos = seq, 0
            self.midstream = True
        start = self._at(seq)
        end = start + len(payload)
        if end == self.pos and len(payload) == 1:  # a keep-alive probe: one byte (garbage) at pos - 1
            return []
        if start < self.pos:  # a retransmission, maybe overlapping new bytes
            self._compare_recent(start, payload)
            if end <= self.pos:
                self.copies += 1
                return []
            payload = payload[self.pos - start :]
            start = self.pos
        out: list[Chunk] = []
        if start == self.pos:
            out.append(Chunk(time, payload, midstream=self.midstream))
            self.midstream = False
            self._delivered(payload)
            if self.waiting:
                out += self._drain()
            return out
        held = self.waiting.get(start)
        while held is not None and len(held[1]) < len(payload):
            # a longer retransmission: the held bytes keep their (earlier) time, the ones past
            # them wait on their own, unless held there too (each byte has its first arrival's time)
            self._compare(held[1], payload)
            payload, start = payload[len(held[1]) :], start + len(held[1])
            held = self.waiting.get(start)
        if held is not None:
            self._compare(held[1], payload)
        else:
            heapq.heappush(self._starts, start)
            self.waiting[start] = (time, payload)
            self._arrivals.append((time, start))
            self.waiting_bytes += len(payload)
        while self.waiting and (self.waiting_bytes > MAX_WAITING or time - self._oldest() > HOLE_SECONDS):
            out += self.skip_gap()
        return out

    def _oldest(self) -> float:
        """Capture time of the oldest segment still waiting (queue entries of gone ones dropped)."""
        arrivals, waiting = self._arrivals, self.waiting
        while arrivals:
            time, start = arrivals[0]
            held = waiting.get(start)
            if held is not None and held[0] == time:
                return time
            arrivals.popleft()
        return 0.0

    def _delivered(self, data: bytes) -> None:
        """Bytes delivered in order: the last of them kept, between RECENT and 2 x RECENT (one
        trim per RECENT bytes), always the bytes just before `pos` (a chunk longer than RECENT,
        as segmentation offload gives, replaces them)."""
        self.pos += len(data)
        recent = self._recent
        if len(data) >= RECENT:
            recent[:] = data[-RECENT:]
            return
        recent += data
        if len(recent) > 2 * RECENT:
            del recent[: len(recent) - RECENT]

    def _compare(self, kept: bytes, other: bytes) -> None:
        n = min(len(kept), len(other))
        if kept[:n] != other[:n]:
            self.conflicts += 1
            self.conflict_bytes += n

    def _compare_recent(self, start: int, payload: bytes) -> None:
        """A retransmission of delivered bytes: compared where they are still known."""
        known_from = self.pos - len(self._recent)
        lo = max(start, known_from)
        hi = min(start + len(payload), self.pos)
        if lo < hi:
            kept = bytes(self._recent[lo - known_from : hi - known_from])
            self._compare(kept, payload[lo - start : hi - start])

    def _drain(self) -> list[Chunk]:
        """Deliver what waits from `pos` on, until the next hole."""
        out: list[Chunk] = []
        starts, waiting = self._starts, self.waiting
        while starts and starts[0] <= self.pos:
            start = heapq.heappop(starts)
            found = waiting.pop(start, None)
            if found is None:
                continue
            time, payload = found
            self.waiting_bytes -= len(payload)
            if start < self.pos:
                self._compare_recent(start, payload)
                if start + len(payload) <= self.pos:
                    continue
                payload = payload[self.pos - start :]
            out.append(Chunk(time, payload))
            self._delivered(payload)
        return out

    def in_order_at(self, seq: int) -> bool:
        """Whether a segment at `seq` would be delivered as it is: next in order, nothing waiting."""
        return self.next_seq == seq and not self.waiting

    def advance(self, size: int, tail: bytes, step: int) -> None:
        """Account for `size` bytes delivered in order outside `feed`: a run of whole packages of
        `step` bytes, `tail` the last of them (2 x RECENT, or all). What is kept to compare
        copies with is what delivering them one by one keeps."""
        assert self.base is not None
        recent = self._recent
        held = len(recent)
        if step >= RECENT:
            keep = RECENT
        elif held + size <= 2 * RECENT:
            keep = held + size
        else:  # trimmed to RECENT once past 2 x RECENT, then again every RECENT // step + 1 packages
            first = (2 * RECENT - held) // step + 1
            keep = RECENT + (size // step - first) % (RECENT // step + 1) * step
        if keep > size:
            recent[:] = recent[held - (keep - size) :] + tail[-size:]
        else:
            recent[:] = tail[-keep:]
        self.pos += size

    def skip_gap(self) -> list[Chunk]:
        """Declare the hole before the earliest waiting segment lost; deliver up to the next hole."""
        starts, waiting = self._starts, self.waiting
        while starts and starts[0] not in waiting:
            heapq.heappop(starts)
        if not starts or self.base is None:
            return []
        lost = starts[0] - self.pos
        self.gaps += 1
        self.lost_bytes += lost
        self.pos = starts[0]
        self._recent.clear()  # the bytes before the hole are no longer next to these
        chunks = self._drain()
        if chunks:
            chunks[0].gap_before = lost
        return chunks

    def acked(self, ack: int) -> list[Chunk]:
        """The peer's acknowledgment number: the bytes before it reached the peer, so a hole before
        it is not in the capture and never will be (Wireshark: "ACKed segment that wasn't
        captured"). Such holes are declared lost now, not after HOLE_SECONDS of this direction's
        own segments: what waits behind them is decoded in its place among the other direction's."""
        out: list[Chunk] = []
        if self.base is None or not self.waiting:
            return out
        upto = self._at(ack)
        starts, waiting = self._starts, self.waiting
        while waiting:
            while starts[0] not in waiting:
                heapq.heappop(starts)
            if starts[0] > upto:
                break
            out += self.skip_gap()
        return out

    def drain(self) -> list[Chunk]:
        """At the end of the capture: every hole still open is lost; deliver everything after them."""
        out: list[Chunk] = []
        while self.waiting:
            out += self.skip_gap()
        return out
