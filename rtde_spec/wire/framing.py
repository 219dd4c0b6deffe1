"""Cut a TCP byte stream into whole RTDE packages, whatever the read boundaries."""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Any

from rtde_spec._generated.constants import RTDE_HEADER_FORMAT as HEADER_FORMAT
from rtde_spec.errors import DecodeError, UsageError

_HEADER = struct.Struct(HEADER_FORMAT)
_SIZE_BYTES = struct.calcsize(HEADER_FORMAT[:2])  # the size field leads the header
HEADER_SIZE = _HEADER.size


@dataclass
class Skipped:
    """What a lenient decoder skipped because it did not decode: how many, their bytes, the first few."""

    count: int = 0
    bytes: int = 0
    first: list[tuple[int, str]] = field(default_factory=list)  # (stream offset, reason)
    keep: int = 10

    def add(self, offset: int, size: int, reason: str) -> None:
        self.count += 1
        self.bytes += size
        if len(self.first) < self.keep:
            self.first.append((offset, reason))


class PackageFramer:
    """Feed it bytes as they arrive; it returns each complete package once.

    Works for any protocol whose packages start with a big-endian size that counts
    the whole package (RTDE: uint16, primary interface: uint32). A size below the
    header size, or above `max_size`, cannot be resynchronised from: it raises
    DecodeError with the stream offset, and keeps raising on later feeds (and on
    close); the packages that feed completed before the fault are in `salvaged`,
    and `pending` counts the bytes from the fault on. Sizes are checked before
    anything is buffered for them, so a claimed size costs nothing until its bytes
    arrive; each byte is copied into the buffer once and moved at most once (the
    unfinished package left after a drain), so framing stays linear in the input.
    """

    def __init__(
        self, size_bytes: int = _SIZE_BYTES, header_size: int = HEADER_SIZE, max_size: int | None = None
    ) -> None:
        self._size_bytes = size_bytes
        self._header_size = header_size
        self._max_size = max_size
        self._buf = bytearray()
        self._start = 0  # index in _buf of the first unconsumed byte
        self._offset = 0  # stream offset of _buf[_start]
        self._broken: DecodeError | None = None
        self.salvaged: list[tuple[int, Any]] = []  # packages of the feed that broke, before the fault

    @property
    def offset(self) -> int:
        """Stream offset of the next package's first byte."""
        return self._offset

    @property
    def pending(self) -> int:
        """Bytes held that do not yet make a whole package."""
        return len(self._buf) - self._start

    def feed(
        self, data: bytes | bytearray | memoryview, run: tuple[int, bytes] | None = None
    ) -> list[tuple[int, bytes]]:
        """Add bytes; return (stream offset, package bytes) for every package completed.

        With `run` = (package size, leading bytes), back-to-back packages of that size
        starting with those bytes come out together as one item (several packages'
        bytes), found with one strided comparison per leading byte: the fast path for
        data packages.
        A run at the start of a `bytes` input, with nothing held, is a memoryview of
        that input rather than a copy (bytes cannot change under it).
        """
        if self._broken is not None:
            raise self._broken
        out: list[tuple[int, Any]] = []
        self.salvaged = out
        if run is not None and isinstance(data, bytes):
            data = self._run_in_place(data, run, out)
        try:
            self._buf += data
        except TypeError:  # "can't concat str to bytearray"
            as_bytes(data, "feed")
            raise
        self._drain(run, out)
        return out

    def take_whole(self, size: int) -> int | None:
        """The stream offset of a read that is one whole package of `size` bytes (its header
        checked by the caller), now counted as framed; None while bytes are held or the stream
        is broken (then `feed` frames it). A 10 Hz client's every read: one call, no checks of
        the bytes themselves."""
        if self._start != len(self._buf) or self._broken is not None:
            return None
        at = self._offset
        self._offset = at + size
        return at

    def take_run(self, data: bytes, size: int, lead: bytes) -> int:
        """How many packages `data` is, when it is only whole packages of `size` that each begin
        with `lead` and nothing is held (then they count as framed); else 0.

        What a client's read usually is (a read ends where a TCP segment does): it skips
        the general path.
        """
        if not data or len(data) % size or self._start != len(self._buf) or self._broken is not None:
            return 0
        count = len(data) // size
        if not (data.startswith(lead) if count == 1 else _run_length(data, 0, size, lead) == count):
            return 0
        self._offset += len(data)
        return count

    def _drain(self, run: tuple[int, bytes] | None, out: list[tuple[int, Any]]) -> None:
        """Every whole package held in the buffer to `out`; a partial one stays."""
        buf, start = self._buf, self._start
        while len(buf) - start >= self._size_bytes:
            if run is not None and buf.startswith(run[1], start):
                count = _run_length(buf, start, run[0], run[1])
                if count:
                    end = start + count * run[0]
                    with memoryview(buf) as view:  # one copy, released before the buffer shrinks
                        out.append((self._offset, bytes(view[start:end])))
                    self._offset += end - start
                    start = end
                    continue
            size = int.from_bytes(buf[start : start + self._size_bytes], "big")
            if size < self._header_size or (self._max_size is not None and size > self._max_size):
                low = size < self._header_size
                self._broken = DecodeError(
                    "package size is smaller than the header; the stream cannot be framed"
                    if low
                    else "package size is larger than any message; the stream cannot be framed",
                    field="size",
                    offset=self._offset,
                    expected=f">= {self._header_size}" if low else f"<= {self._max_size}",
                    actual=size,
                )
                self._start = start  # `pending`: the bytes from the fault on
                raise self._broken
            if len(buf) - start < size:
                break
            out.append((self._offset, bytes(buf[start : start + size])))
            start += size
            self._offset += size
        if start:
            del buf[:start]
        self._start = 0

    def _run_in_place(self, data: bytes, run: tuple[int, bytes], out: list[tuple[int, Any]]) -> bytes:
        """The run in immutable `data` as a view of it (no copy); returns what is left to buffer.

        A package begun in the last feed is completed from the head of `data` first
        (a small copy), so the run after it is found in place too.
        """
        start = 0
        held = len(self._buf) - self._start
        if held >= self._size_bytes:
            size = int.from_bytes(self._buf[self._start : self._start + self._size_bytes], "big")
            if self._header_size <= size and 0 < size - held <= len(data):
                start = size - held
                self._buf += data[:start]
                self._drain(run, out)
        if len(self._buf) != self._start or not data.startswith(run[1], start):
            return data[start:] if start else data
        count = _run_length(data, start, run[0], run[1])
        if not count:
            return data[start:] if start else data
        end = start + count * run[0]
        out.append((self._offset, memoryview(data)[start:end]))
        self._offset += end - start
        return data[end:]

    def passed(self, count: int) -> None:
        """Count `count` bytes of whole packages a reader took itself (as `take_run` would, while
        nothing was held), so that later offsets stay those of the stream."""
        self._offset += count

    def close(self) -> None:
        """Raise DecodeError if the stream ended inside a package (or could not be framed)."""
        if self._broken is not None:
            raise self._broken
        if self.pending:
            need = None
            if self.pending >= self._size_bytes:
                need = int.from_bytes(self._buf[self._start : self._start + self._size_bytes], "big")
            raise DecodeError(
                "the data ends inside a package (truncated)",
                field="size" if need is not None else None,
                offset=self._offset,
                expected=f"{need} bytes" if need is not None else f">= {self._header_size} bytes",
                actual=f"{self.pending} bytes",
            )


def as_bytes(data: Any, what: str) -> bytes:
    """`data` as bytes: bytes, bytearray, memoryview or another buffer (a numpy array). Text or a
    number is a UsageError saying what to pass: bytes(text) raised "string argument without an
    encoding", and bytes(5) made five zero bytes to decode."""
    if isinstance(data, bytes):
        return data
    if not isinstance(data, (str, int)):
        try:
            return bytes(data)
        except (TypeError, ValueError):
            pass
    hint = "; hex text: bytes.fromhex(text)" if isinstance(data, str) else ""
    raise UsageError(f"{what} takes bytes (bytes, bytearray, memoryview), not {type(data).__name__}{hint}")


def check_header(
    buf: bytes,
    header: struct.Struct,
    *,
    what: str,
    max_size: int | None = None,
    strict: bool = False,
    hint: str = "",
) -> tuple[int, int]:
    """(size, type) of the package or message at the start of `buf`, checked against it.

    The size counts the whole package, header included. With strict, bytes after
    it are an error too (`hint` says what to use for several).
    """
    hsize = header.size
    if len(buf) < hsize:
        size_bytes = struct.calcsize(header.format[:2])
        raise DecodeError(
            f"too short for the {what} header",
            field="size" if len(buf) < size_bytes else "type",
            offset=len(buf),
            expected=f"{hsize} bytes",
            actual=f"{len(buf)} bytes",
        )
    size, kind = header.unpack_from(buf)
    if size < hsize:
        raise DecodeError(
            f"{what} size is smaller than the header",
            field="size",
            offset=0,
            expected=f">= {hsize}",
            actual=size,
        )
    if max_size is not None and size > max_size:
        raise DecodeError(
            f"{what} size is larger than any {what}",
            field="size",
            offset=0,
            expected=f"<= {max_size}",
            actual=size,
        )
    if size > len(buf):
        raise DecodeError(
            f"{what} is truncated: its size field runs past the data",
            field="size",
            offset=len(buf),
            expected=f"{size} bytes",
            actual=f"{len(buf)} bytes",
        )
    if strict and size < len(buf):
        raise DecodeError(
            f"{len(buf) - size} bytes after the {what}{hint}",
            offset=size,
            expected=f"{size} bytes",
            actual=f"{len(buf)} bytes",
        )
    return size, kind


def _run_length(buf: bytes | bytearray, start: int, size: int, lead: bytes) -> int:
    """How many whole packages of `size` from `start` all begin with `lead`.

    One strided slice per lead byte (its value in every package), stripped of that
    value: C loops without numpy, whose import alone starts a BLAS thread in a client.
    """
    whole = (len(buf) - start) // size
    count = whole
    end = start + whole * size
    for i in range(len(lead)):
        column = buf[start + i : end : size]
        count = min(count, whole - len(column.lstrip(lead[i : i + 1])))
    return count
