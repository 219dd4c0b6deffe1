"""TCP streams: reassembly of one direction of one connection (the layer after packets).

In order: data is delivered at once. Retransmitted and overlapping segments deliver
only the bytes not seen yet. Out-of-order segments wait behind the hole before them
for its retransmission, which a sender makes within its retransmission time-out
(200 ms and up). When the hole has waited HOLE_SECONDS of capture time, or more than
MAX_WAITING bytes wait, it is declared lost: it is counted as a gap of so many bytes
and delivery resumes after it; the framing above then looks for the next package.
At the end of the capture every hole still open is declared lost (`drain`), so data
after any number of holes is delivered. This module knows nothing of the protocols.
"""

from __future__ import annotations

from dataclasses import dataclass, field

MOD = 1 << 32
HALF = MOD // 2
MAX_WAITING = 1 << 20  # bytes held behind a hole before it is declared lost: bounds memory
HOLE_SECONDS = 2.0  # capture seconds a hole waits for its retransmission (TCP's RTO is 0.2 s to ~1 s)


@dataclass
class Chunk:
    time: float
    data: bytes
    gap_before: int = 0  # bytes lost just before this chunk (a hole declared lost)
    midstream: bool = False  # the first chunk of a stream whose start (SYN) is not in the capture


@dataclass
class Direction:
    next_seq: int | None = None
    waiting: dict[int, tuple[float, bytes]] = field(default_factory=dict)
    waiting_bytes: int = 0
    waiting_since: float = 0.0  # capture time of the oldest segment waiting
    gaps: int = 0
    lost_bytes: int = 0
    midstream: bool = False  # no SYN seen: the next chunk delivered is the first, from mid-stream

    def feed(self, time: float, seq: int, payload: bytes, syn: bool = False) -> list[Chunk]:
        if syn:
            self.next_seq = (seq + 1) % MOD
            return []
        if not payload:
            return []
        out: list[Chunk] = []
        if self.next_seq is None:  # a capture that starts mid-stream
            self.next_seq = seq
            self.midstream = True
        offset = (seq - self.next_seq) % MOD
        if offset >= HALF:  # at or before next_seq: a retransmission, maybe overlapping
            already = (self.next_seq - seq) % MOD
            if already >= len(payload):
                return out
            payload = payload[already:]
            offset = 0
        if offset == 0:
            out.append(Chunk(time, payload, midstream=self.midstream))
            self.midstream = False
            self.next_seq = (self.next_seq + len(payload)) % MOD
            if self.waiting:
                out += self._drain()
            return out
        held = self.waiting.get(seq)
        if held is None or len(held[1]) < len(payload):  # a longer retransmission replaces a shorter
            if not self.waiting:
                self.waiting_since = time
            self.waiting[seq] = (time, payload)
            self.waiting_bytes += len(payload) - (len(held[1]) if held else 0)
        while self.waiting and (self.waiting_bytes > MAX_WAITING or time - self.waiting_since > HOLE_SECONDS):
            out += self.skip_gap()
        return out

    def _drain(self) -> list[Chunk]:
        """Deliver what waits from next_seq on, until the next hole."""
        out: list[Chunk] = []
        waiting = self.waiting
        while waiting:
            assert self.next_seq is not None
            found = waiting.pop(self.next_seq, None)
            if found is not None:  # the usual case: the segment that follows exactly
                time, payload = found
                self.waiting_bytes -= len(payload)
                out.append(Chunk(time, payload))
                self.next_seq = (self.next_seq + len(payload)) % MOD
                continue
            nxt = self.next_seq
            ready = [s for s in waiting if (s - nxt) % MOD >= HALF]  # starting before next_seq
            if not ready:
                break
            for s in sorted(ready, key=lambda s: (s - nxt) % MOD):
                time, payload = waiting.pop(s)
                self.waiting_bytes -= len(payload)
                already = (self.next_seq - s) % MOD
                if already < HALF and already < len(payload):
                    out.append(Chunk(time, payload[already:]))
                    self.next_seq = (self.next_seq + len(payload) - already) % MOD
        if waiting:
            self.waiting_since = min(t for t, _ in waiting.values())
        return out

    def in_order_at(self, seq: int) -> bool:
        """Whether a segment at `seq` would be delivered as it is: next in order, nothing waiting."""
        return self.next_seq == seq and not self.waiting

    def advance(self, size: int) -> None:
        """Account for `size` bytes delivered in order outside `feed` (a run of whole packages)."""
        assert self.next_seq is not None
        self.next_seq = (self.next_seq + size) % MOD

    def skip_gap(self) -> list[Chunk]:
        """Declare the hole before the earliest waiting segment lost; deliver up to the next hole."""
        if not self.waiting or self.next_seq is None:
            return []
        nxt = self.next_seq
        first = min(self.waiting, key=lambda s: (s - nxt) % MOD)
        lost = (first - nxt) % MOD
        self.gaps += 1
        self.lost_bytes += lost
        self.next_seq = first
        chunks = self._drain()
        if chunks:
            chunks[0].gap_before = lost
        return chunks

    def drain(self) -> list[Chunk]:
        """At the end of the capture: every hole still open is lost; deliver everything after them."""
        out: list[Chunk] = []
        while self.waiting:
            out += self.skip_gap()
        return out
