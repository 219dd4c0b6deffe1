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
        times: list[float] = []
        while len(buf) - pos >= self.header:
            size = self.plausible(pos)
            if size is None:  # not a header where one must be: treat as lost sync
                del buf[:pos]
                self.synced = False
                self.lost_sync += 1
                marks, self.marks = [], [(len(buf), now)]
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
                while marks and marks[0][0] < pos:
                    marks.pop(0)
                times.append(marks[0][1] if marks else now)
        if self.synced:
            del buf[:pos]
        if len(times) == len(out) and any(t != now for t in times):
            self.times = times
        return out

    def _resync(self, final: bool) -> bool:
        if not self.found_start and self._fills_exactly():
            return self._synced_at(0)  # a stream captured from its middle, its segments whole packages
        strong = self._find_strong()
        if strong is not None:
            for at in range(strong):  # a candidate before it counts if its headers lead onto it
                if self._leads_to(at, strong):
                    return self._synced_at(at)
            return self._synced_at(strong)
        if not final and len(self.buf) < WINDOW:
            return False  # wait for a package the protocol vouches for
        return self._confirmed(final)

    def _find_strong(self) -> int | None:
        """The first candidate the check vouches for, searched from where the last search ended
        (or from the first one too short to judge then)."""
        buf, last = self.buf, len(self.buf) - self.header
        unfinished = None
        for at in range(self.scan_from, last + 1):
            size = self.plausible(at)
            if size is None:
                continue
            verdict = self.check(buf, at, size)
            if verdict == STRONG:
                return at
            if verdict == WEAK and at + size > len(buf) and unfinished is None:
                unfinished = at
        self.scan_from = max(0, last + 1) if unfinished is None else unfinished
        return None

    def _fills_exactly(self) -> bool:
        """Whether the held bytes are whole packages from the first byte to the last.

        A capture that starts after the handshake starts at a segment, and senders write
        packages whole: headers that chain from the first byte exactly to the end are the
        boundary, so the setup exchange a client sends is decoded when it comes, not held
        for a window it never fills (its replies' data would wait for it, unknown)."""
        at, end = 0, len(self.buf)
        while at < end:
            size = self.plausible(at)
            if size is None or at + size > end or self.check(self.buf, at, size) == NO:
                return False
            at += size
        return end > 0

    def _leads_to(self, at: int, strong: int) -> bool:
        while at < strong:
            size = self.plausible(at)
            if size is None or self.check(self.buf, at, size) == NO:
                return False
            at += size
        return at == strong

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
        self.scan_from = 0
        return True

    def _skip(self, count: int) -> None:
        if count:
            if self.found_start:
                self.skipped += count
            else:
                self.lead_in += count
            del self.buf[:count]
            self.scan_from = max(0, self.scan_from - count)
            self.marks = [(end - count, t) for end, t in self.marks if end > count]
