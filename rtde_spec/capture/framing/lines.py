"""Framing of protocols without a size header: fixed-size records (URCL's external control)
and text lines (the dashboard server, the script sender's request).

Fixed records need no search after a gap: TCP says how many bytes were lost, so the
next record boundary is known exactly; the record the gap cut is counted (`cut`) with
the bytes passed over (`skipped`). Only a stream captured from its middle has an
unknown boundary: the first offset whose next records all look like records (the
protocol's `plausible`: a known variant, enum words of known values) is taken, the
bytes before it are `lead_in`. Lines resume after the next newline following a gap.
The attribute names are those of `framing.Framing`, so the summary reads all alike.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

from rtde_spec.capture.tcp import Chunk

CONFIRM = 3  # records that must look right at an offset before a mid-stream capture is cut there
WINDOW = 64 << 10  # bytes held looking for that offset


class FixedFraming:
    """Cut one direction's bytes into records of `size` bytes."""

    def __init__(self, size: int, plausible: Callable[[bytes, int], bool]) -> None:
        self.size, self.plausible = size, plausible
        self.buf = bytearray()
        self.synced = True
        self.to_skip = 0  # bytes of a record cut by a gap still to pass over
        self.skipped = self.cut = self.lead_in = 0
        self.unaligned = False  # no offset ever looked right: decoded from where the stream began
        self.phase = 0  # unsynced: the first offset not yet refused
        self.times: list[float] | None = None  # of the records the last call gave, when not all its chunk's
        self.marks: list[tuple[int, float]] = []  # unsynced: (end in buf, time) of each chunk held

    def feed(self, chunk: Chunk) -> list[bytes]:
        self.times = None
        if chunk.midstream:
            self.synced = False
        if chunk.gap_before:
            held = len(self.buf)
            if self.synced:
                into = (held + chunk.gap_before) % self.size  # where in a record the data resumes
                self.to_skip = (self.size - into) % self.size
                self.cut += 1 if held or self.to_skip else 0
                self.skipped += held
                self.buf.clear()
            # unsynced: the offset is searched in what follows; the hole just shifts it
        data = chunk.data
        if self.to_skip:
            n = min(self.to_skip, len(data))
            self.to_skip -= n
            self.skipped += n
            data = data[n:]
        self.buf += data
        if not self.synced:
            self.marks.append((len(self.buf), chunk.time))
            if not self._align(final=False):
                return []
        return self._records()

    def at_boundary(self, size: int) -> bool:
        """Whether records of `size` bytes fed now would come out as they are: the same size, in
        sync, nothing held or to pass over (a run of whole records may skip `feed`)."""
        return self.size == size and self.synced and not self.buf and not self.to_skip

    def finish(self) -> list[bytes]:
        """The end of the stream: a mid-stream capture too short to confirm is aligned as it can be."""
        self.times = None
        if self.synced or not self.buf:
            return []
        self._align(final=True)
        return self._records()

    def _records(self) -> list[bytes]:
        """The whole records held; those held while the offset was searched keep the time of the
        chunk that completed each (`times`), not the time of the one that confirmed the offset."""
        size, buf = self.size, self.buf
        whole = len(buf) - len(buf) % size
        out = [bytes(buf[i : i + size]) for i in range(0, whole, size)]
        del buf[:whole]
        marks, self.marks = self.marks, []
        if marks and len({t for _, t in marks}) > 1:
            times, mark = [], 0
            for end in range(size, whole + 1, size):
                while marks[mark][0] < end:
                    mark += 1
                times.append(marks[mark][1])
            self.times = times
        return out

    def _align(self, final: bool) -> bool:
        """Find the first offset whose next records look right. An offset once refused stays
        refused (its records do not change as bytes arrive), so each is judged once and a
        stream fed byte by byte costs its length, not its length times the record size."""
        buf, size = self.buf, self.size
        need = CONFIRM if not final else max(1, min(CONFIRM, len(buf) // size))
        if final:  # fewer records may confirm an offset now: every offset is judged again
            self.phase = 0
        while self.phase < min(size, max(0, len(buf) - size + 1)):
            phase = self.phase
            if len(buf) - phase < need * size:
                if not final:
                    return False  # wait for enough records at this offset
                break
            data = bytes(buf[phase : phase + need * size])
            if all(self.plausible(data, k * size) for k in range(need)):
                self.lead_in += phase
                del buf[:phase]
                self.marks = [(end - phase, t) for end, t in self.marks if end > phase]
                self.synced = True
                self.phase = 0
                return True
            self.phase += 1
        if final or len(buf) >= WINDOW or self.phase >= size:
            self.unaligned = True  # nothing looks like a record: decode from the first byte
            self.synced = True
            self.phase = 0
            return True
        return False


def run_records(rows: Any) -> list[bytes]:
    """A run's numpy rows (one whole record each) as the records framing would give."""
    size, data = rows.shape[1], rows.tobytes()
    return [data[at : at + size] for at in range(0, len(data), size)]


def run_chunks(rows: Any, when: list[float]) -> Iterator[Chunk]:
    """A run's rows as the chunks TCP reassembly gives for segments in order, one a segment."""
    for time, row in zip(when, rows, strict=True):
        yield Chunk(time, row.tobytes())


class LineFraming:
    """Cut one direction's bytes into lines (without their newline); `limit` bounds a line.

    After a gap the bytes up to the next newline are the tail of a line whose start was lost,
    and are passed over, unless `whole` says they read as a line of their own: a sender that
    writes each line in one send starts a segment with a line, so the bytes lost were the rest
    of the line cut (a snap length) or whole lines (a dropped segment)."""

    def __init__(self, limit: int, whole: Callable[[bytes], bool] | None = None) -> None:
        self.limit = limit
        self.whole = whole
        self.buf = bytearray()
        self.resync = False  # after a gap (or an over-long line): drop bytes up to the next newline
        self.skipped = self.cut = self.lead_in = 0
        self.too_long = 0
        self.times: list[float] | None = None

    def feed(self, chunk: Chunk) -> list[bytes]:
        if chunk.gap_before:  # the line the gap cut is lost; the next begins after a newline
            self.cut += 1
            self.skipped += len(self.buf)
            self.buf.clear()
            self.resync = True
        data = chunk.data
        if self.resync:
            at = data.find(b"\n")
            if (
                at >= 0
                and chunk.gap_before
                and self.whole is not None
                and self.whole(data[:at].rstrip(b"\r"))
            ):
                at = -1  # the chunk after the gap starts with a whole line: nothing to pass over
            elif at < 0:
                self.skipped += len(data)
                return []
            self.skipped += at + 1
            data = data[at + 1 :]
            self.resync = False
        self.buf += data
        lines = self.buf.split(b"\n")
        rest = lines.pop()
        self.buf = bytearray(rest)
        if len(self.buf) > self.limit:  # no line is this long: drop it up to its end
            self.too_long += 1
            self.skipped += len(self.buf)
            self.buf.clear()
            self.resync = True
        out = []
        for line in lines:
            if len(line) > self.limit:  # dropped whole too: the same line in pieces is dropped above
                self.too_long += 1
                self.skipped += len(line) + 1
                continue
            out.append(bytes(line.rstrip(b"\r")))
        return out

    def finish(self) -> list[bytes]:
        """A last line without its newline (a reply cut by the end of the capture) is kept."""
        if not self.buf:
            return []
        line, self.buf = bytes(self.buf), bytearray()
        return [line]
