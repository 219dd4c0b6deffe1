"""Protocol framing: one direction's reassembled bytes cut into packages (the layer after TCP streams).

Both protocols frame by a header of a big-endian size and a type. In sync, every
header is taken as it says. After a gap (or a header that cannot be one) the bytes
are searched for the next boundary. A candidate is a plausible header (size within
limits, a known type) that the protocol's own `Check` does not refuse; the check
vouches for some (STRONG: for RTDE a data package of a known recipe's id and size,
for primary a message its sub-packages fill exactly). The boundary taken is the
first candidate whose chain of headers leads exactly onto a vouched-for one (so a
text message just before a data package is kept), else that vouched-for one. Up to
WINDOW bytes are held waiting for one; without (no recipe known, the end of the
stream), a candidate the next header confirms is taken. Two headers alone are not
trusted first: a float that repeats package after package can look like a header
at the same place in every package. Bytes passed over are counted (`skipped`), and
so are packages cut by a gap (`cut`). Packages held back are given the time of the
chunk that completed them (`times`).
"""

from __future__ import annotations

import heapq
from collections.abc import Callable

from rtde_spec.capture.tcp import Chunk

NO, WEAK, STRONG = 0, 1, 2  # what a Check says of a candidate: not one, maybe, surely
Check = Callable[[bytearray, int, int], int]  # (buffer, start, size) -> NO | WEAK | STRONG
WINDOW = 64 << 10  # bytes held after a gap waiting for a package the protocol vouches for


def any_package(buf: bytearray, at: int, size: int) -> int:
    return WEAK


class Framing:
    """Cut one direction's bytes into packages; after a gap, find the next package boundary."""

    def __init__(
        self, size_bytes: int, header: int, types: set[int], max_size: int, check: Check = any_package
    ) -> None:
        self.size_bytes, self.header, self.types, self.max_size = size_bytes, header, types, max_size
        self.check = check
        self.buf = bytearray()
        self.synced = True
        self.skipped = 0  # bytes passed over: packages cut by a gap, bytes that are no package
        self.cut = 0  # packages begun before a gap and never completed
        self.lost_sync = 0  # headers found where none could be, in sync
        self.lead_in = 0  # bytes before the first boundary of a stream captured from its middle
        self.found_start = True  # False until the first boundary of a stream captured from its middle
        self.scan_from = 0  # where the search for a vouched-for candidate goes on
        self.unjudged: list[tuple[int, int]] = []  # heap of (end, start) of candidates not whole yet,
        # as absolute stream offsets: each is judged once, when its last byte arrives
        self.dropped = 0  # bytes deleted from the front of `buf` while searching (its absolute offset)
        self.filled = 0  # how far whole packages chain from the first byte held (mid-stream start)
        self.marks: list[tuple[int, float]] = []  # unsynced: (end in buf, time) of each chunk held
        self.times: list[float] | None = None  # of the packages the last call gave, when not all `now`

    def plausible(self, at: int) -> int | None:
        buf = self.buf
        if len(buf) - at < self.header:
            return None
        size = int.from_bytes(buf[at : at + self.size_bytes], "big")
        if size < self.header or size > self.max_size or buf[at + self.size_bytes] not in self.types:
            return None
        return size

    def feed(self, chunk: Chunk) -> list[bytes]:
        out: list[bytes] = []
        times: list[float] = []
        if chunk.midstream:  # the first bytes of a stream whose start is not in the capture
            self.synced = self.found_start = False
        if chunk.gap_before:
            if self.buf and not self.synced:  # held for confirmation: decode what can be, first
                out = self._frame(final=True, now=chunk.time)
                times = self.times or [chunk.time] * len(out)
            if self.buf:  # a package begun before the gap: its end is lost
                self.cut += 1
                self._skip(len(self.buf))
            self.synced = False
            self.marks.clear()
        self.buf += chunk.data
        if not self.synced:
            self.marks.append((len(self.buf), chunk.time))
        more = self._frame(final=False, now=chunk.time)
        if out:
            self.times = times + (self.times or [chunk.time] * len(more))
            return out + more
        return more

    def finish(self) -> list[bytes]:
        """At the end of the stream: what the search held back, as far as whole."""
        self.times = None
        if not self.buf or self.synced:
            return []
        return self._frame(final=True, now=self.marks[-1][1] if self.marks else 0.0)

    def _frame(self, final: bool, now: float) -> list[bytes]:
        self.times = None
        if not self.synced and not self._resync(final):
            return []
        out: list[bytes] = []
        pos = 0
        buf = self.buf
        marks, self.marks = self.marks, []
        mark = 0  # the first of `marks` not yet passed (an index: popping the front is quadratic)
        times: list[float] = []
        while len(buf) - pos >= self.header:
            size = self.plausible(pos)
            if size is None:  # not a header where one must be: treat as lost sync
                del buf[:pos]
                self.synced = False
                self.lost_sync += 1
                marks, mark, self.marks = [], 0, [(len(buf), now)]
                if not self._resync(final):
                    break
                self.marks = []
                pos = 0
                continue
            if len(buf) - pos < size:
                break
            out.append(bytes(buf[pos : pos + size]))
            pos += size
            if marks:
                while mark < len(marks) and marks[mark][0] < pos:
                    mark += 1
                times.append(marks[mark][1] if mark < len(marks) else now)
        if self.synced:
            del buf[:pos]
        if len(times) == len(out) and any(t != now for t in times):
            self.times = times
        return out

    def _resync(self, final: bool) -> bool:
        if not self.found_start and self._fills_exactly():
            return self._synced_at(0)  # a stream captured from its middle, its segments whole packages
        strong = self._find_strong()
        if strong is not None:  # a candidate before it counts if its headers lead onto it
            return self._synced_at(self._first_leading_to(strong))
        if not final and len(self.buf) < WINDOW:
            return False  # wait for a package the protocol vouches for
        return self._confirmed(final)

    def _find_strong(self) -> int | None:
        """The first candidate the check vouches for among those that can be judged now.

        Each offset is looked at once: new offsets from where the last search ended, and a
        candidate not yet whole again only when its last byte has arrived (a heap by its
        end), so a stream fed byte by byte costs its length, not its length squared."""
        buf, last, dropped = self.buf, len(self.buf) - self.header, self.dropped
        found: int | None = None
        unjudged = self.unjudged
        while unjudged and unjudged[0][0] - dropped <= len(buf):
            _, start = heapq.heappop(unjudged)
            at = start - dropped
            if at < 0 or (found is not None and at >= found):
                continue
            size = self.plausible(at)
            if size is not None and self.check(buf, at, size) == STRONG:
                found = at
        for at in range(self.scan_from, last + 1):
            if found is not None and at >= found:
                break
            size = self.plausible(at)
            if size is None:
                continue
            verdict = self.check(buf, at, size)
            if verdict == STRONG:
                found = at
                break
            if verdict == WEAK and at + size > len(buf):
                heapq.heappush(unjudged, (at + size + dropped, at + dropped))
        if found is not None:
            return found
        self.scan_from = max(self.scan_from, last + 1)
        return None

    def _fills_exactly(self) -> bool:
        """Whether the held bytes are whole packages from the first byte to the last.

        A capture that starts after the handshake starts at a segment, and senders write
        packages whole: headers that chain from the first byte exactly to the end are the
        boundary, so the setup exchange a client sends is decoded when it comes, not held
        for a window it never fills (its replies' data would wait for it, unknown)."""
        at, end = self.filled, len(self.buf)
        while at < end:
            size = self.plausible(at)
            if size is None or at + size > end or self.check(self.buf, at, size) == NO:
                return False
            at += size
            self.filled = at  # packages already chained are not walked again
        return end > 0

    def _first_leading_to(self, strong: int) -> int:
        """The first offset whose chain of headers leads exactly onto `strong` (else `strong`).

        Judged from `strong` backwards, each offset once: whether a header leads there is
        looked up where it ends, not walked again from every offset before it (held bytes
        that are all short headers missing `strong` by one cost their length, not its square:
        24 kB of them took 24 s)."""
        leads = bytearray(strong + 1)
        leads[strong] = 1
        first = strong
        for at in range(strong - 1, -1, -1):
            size = self.plausible(at)
            if size is None or at + size > strong or not leads[at + size]:
                continue
            if self.check(self.buf, at, size) != NO:
                leads[at] = 1
                first = at
        return first

    def _confirmed(self, final: bool) -> bool:
        """Without a vouched-for candidate: the first that the next header confirms (or, at the
        end, that is whole)."""
        buf = self.buf
        for at in range(len(buf) - self.header + 1):
            size = self.plausible(at)
            if size is None or self.check(buf, at, size) == NO:
                continue
            following = at + size
            if len(buf) - following >= self.header:  # the next header is here: it must be one too
                if (nxt := self.plausible(following)) is None or self.check(buf, following, nxt) == NO:
                    continue
            elif not (final and following <= len(buf)):
                self._skip(at)  # wait for more bytes to decide
                return False
            return self._synced_at(at)
        self._skip(max(0, len(buf) - self.header + 1))  # keep what may begin a header
        if final:
            self._skip(len(buf))
        return False

    def _synced_at(self, at: int) -> bool:
        self._skip(at)
        self.synced = self.found_start = True
        self.scan_from = self.filled = 0
        self.unjudged.clear()
        return True

    def _skip(self, count: int) -> None:
        if count:
            # before the first boundary of a stream captured from its middle: the tail of a package,
            # so at most one package long; bytes past that are no package at all (damage)
            lead = 0 if self.found_start else min(count, max(0, self.max_size - self.lead_in))
            self.lead_in += lead
            self.skipped += count - lead
            del self.buf[:count]
            self.dropped += count
            self.scan_from = max(0, self.scan_from - count)
            self.filled = 0
            self.marks = [(end - count, t) for end, t in self.marks if end > count]
