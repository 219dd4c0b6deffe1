"""TCP reassembly for one direction of one connection.

In order: data is delivered at once. Retransmitted and overlapping segments deliver
only the bytes not seen yet. Out-of-order segments wait; when too much waits (or
the stream ends) behind a hole, the hole is reported as a gap of so many bytes and
delivery resumes after it: the decoder then looks for the next package boundary.
"""

from __future__ import annotations

from dataclasses import dataclass, field

MOD = 1 << 32
MAX_WAITING = 1 << 20  # bytes held behind a hole before it is declared a gap


@dataclass
class Chunk:
    time: float
    data: bytes
    gap_before: int = 0  # bytes lost just before this chunk


@dataclass
class Direction:
    next_seq: int | None = None
    waiting: dict[int, tuple[float, bytes]] = field(default_factory=dict)
    waiting_bytes: int = 0
    gaps: int = 0
    lost_bytes: int = 0

    def feed(self, time: float, seq: int, payload: bytes, syn: bool = False) -> list[Chunk]:
        if syn:
            self.next_seq = (seq + 1) % MOD
            return []
        if not payload:
            return []
        if self.next_seq is None:  # a capture that starts mid-stream
            self.next_seq = seq
        out: list[Chunk] = []
        offset = (seq - self.next_seq) % MOD
        if offset >= MOD // 2:  # at or before next_seq: a retransmission, maybe overlapping
            already = (self.next_seq - seq) % MOD
            if already >= len(payload):
                return out
            payload = payload[already:]
            offset = 0
        if offset == 0:
            out.append(Chunk(time, payload))
            self.next_seq = (self.next_seq + len(payload)) % MOD
            out += self._drain()
        else:
            if seq not in self.waiting:
                self.waiting[seq] = (time, payload)
                self.waiting_bytes += len(payload)
            if self.waiting_bytes > MAX_WAITING:
                out += self.skip_gap()
        return out

    def _drain(self) -> list[Chunk]:
        out: list[Chunk] = []
        while self.waiting:
            assert self.next_seq is not None
            ready = [s for s in self.waiting if (s - self.next_seq) % MOD >= MOD // 2 or s == self.next_seq]
            if not ready:
                break
            for s in ready:
                time, payload = self.waiting.pop(s)
                self.waiting_bytes -= len(payload)
                already = (self.next_seq - s) % MOD
                if already < len(payload):
                    out.append(Chunk(time, payload[already:]))
                    self.next_seq = (self.next_seq + len(payload) - already) % MOD
        return out

    def in_order_at(self, seq: int) -> bool:
        """Whether a segment at `seq` would be delivered as it is: next in order, nothing waiting."""
        return self.next_seq == seq and not self.waiting

    def advance(self, size: int) -> None:
        """Account for `size` bytes delivered in order outside `feed` (a run of whole packages)."""
        assert self.next_seq is not None
        self.next_seq = (self.next_seq + size) % MOD

    def skip_gap(self) -> list[Chunk]:
        """Declare the hole before the earliest waiting segment lost; deliver from there."""
        if not self.waiting or self.next_seq is None:
            return []
        first = min(self.waiting, key=lambda s: (s - self.next_seq) % MOD)  # type: ignore[operator]
        lost = (first - self.next_seq) % MOD
        self.gaps += 1
        self.lost_bytes += lost
        self.next_seq = first
        chunks = self._drain()
        if chunks:
            chunks[0].gap_before = lost
        return chunks
