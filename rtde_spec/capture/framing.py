"""Protocol framing: one direction's reassembled bytes cut into packages (the layer after TCP streams).

Both protocols frame by a header of a big-endian size and a type. In sync, every
header is taken as it says. After a gap (or a header that cannot be one) the bytes
are searched for the next boundary: a plausible header (size within limits, a
known type) that the protocol's own check accepts (`Check`: for RTDE a data package
must have a known recipe's id and size; for primary, sub-packages must fill their
message exactly), confirmed by the header that follows it. A candidate the check
vouches for strongly is taken as soon as it is whole, so one package per segment
resynchronises on the first package after the gap. Bytes passed over are counted
(`skipped`), and so are packages cut by a gap (`cut`).
"""

from __future__ import annotations

from collections.abc import Callable

from rtde_spec.capture.tcp import Chunk

NO, WEAK, STRONG = 0, 1, 2  # what a Check says of a candidate: not one, maybe, surely
Check = Callable[[bytearray, int, int], int]  # (buffer, start, size) -> NO | WEAK | STRONG


def any_package(buf: bytearray, at: int, size: int) -> int:
    return WEAK


class Framing:
    """Cut one direction's bytes into packages; after a gap, find a boundary that two headers
    (or one the protocol check vouches for) confirm."""

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

    def plausible(self, at: int) -> int | None:
        buf = self.buf
        if len(buf) - at < self.header:
            return None
        size = int.from_bytes(buf[at : at + self.size_bytes], "big")
        if size < self.header or size > self.max_size or buf[at + self.size_bytes] not in self.types:
            return None
        return size

    def feed(self, chunk: Chunk) -> list[bytes]:
        if chunk.midstream:  # the first bytes of a stream whose start is not in the capture
            self.synced = self.found_start = False
        if chunk.gap_before:
            if self.buf:  # a package begun before the gap: its end is lost
                self.cut += 1
                self.skipped += len(self.buf)
                self.buf.clear()
            self.synced = False
        self.buf += chunk.data
        return self._frame(final=False)

    def finish(self) -> list[bytes]:
        """At the end of the stream: what the search held back for confirmation, as far as whole."""
        return self._frame(final=True) if self.buf and not self.synced else []

    def _frame(self, final: bool) -> list[bytes]:
        if not self.synced and not self._resync(final):
            return []
        out: list[bytes] = []
        pos = 0
        buf = self.buf
        while len(buf) - pos >= self.header:
            size = self.plausible(pos)
            if size is None:  # not a header where one must be: treat as lost sync
                del buf[:pos]
                self.synced = False
                self.lost_sync += 1
                if not self._resync(final):
                    return out
                pos = 0
                continue
            if len(buf) - pos < size:
                break
            out.append(bytes(buf[pos : pos + size]))
            pos += size
        del buf[:pos]
        return out

    def _resync(self, final: bool) -> bool:
        buf = self.buf
        for at in range(len(buf) - self.header + 1):
            size = self.plausible(at)
            if size is None:
                continue
            verdict = self.check(buf, at, size)
            if verdict == NO:
                continue
            following = at + size
            if len(buf) - following >= self.header:  # the next header is here: it must be one too
                if (nxt := self.plausible(following)) is None or self.check(buf, following, nxt) == NO:
                    continue
            elif not ((verdict == STRONG or final) and following <= len(buf)):
                self._skip(at)  # wait for more bytes to decide
                return False
            self._skip(at)
            self.synced = self.found_start = True
            return True
        self._skip(max(0, len(buf) - self.header + 1))  # keep what may begin a header
        if final:
            self._skip(len(buf))
        return False

    def _skip(self, count: int) -> None:
        if count:
            if self.found_start:
                self.skipped += count
            else:
                self.lead_in += count
            del self.buf[:count]
