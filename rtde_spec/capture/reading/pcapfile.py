"""Frames out of pcap and pcapng files, a block of the file at a time, with `struct` and numpy.

A general packet library builds an object per header per frame; for a capture of
hundreds of thousands of small RTDE packages that is most of the decode time. Here
the file is taken in 8 MB blocks and each block becomes `Records`: where every whole
frame starts, its length, time and link type, as numpy columns. A regular file is
mapped rather than read (no copy of it into the process, and the pages of each block
done are handed back, so memory stays flat); a pipe is read. A steady stream
(records of one size in a row) is read through strided views of its record headers,
without a Python step per record.

Classic pcap in either byte order with micro- or nanosecond stamps; pcapng sections
(either byte order), interfaces (link type, `if_tsresol`, `if_tsoffset`), enhanced and simple packet
blocks; other blocks are skipped. A cut-off last record is counted in
`stats['truncated']`; frames a snap length cut in `stats['cut_frames']` (`headers.py`).
"""

from __future__ import annotations

import mmap
import os
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from rtde_spec.capture.reading.headers import count_cut, interface, seconds, snap_length
from rtde_spec.capture.reading.mapping import give_back, mapped_file, populate
from rtde_spec.capture.reading.mixed_sizes import next_differs, pcap_pairs, pcap_walked, pcapng_mixed
from rtde_spec.capture.reading.pipes import waiting, widen
from rtde_spec.capture.reading.recordsync import MAX_BLOCK, next_pcap_record, next_pcapng_block, pcap_limit
from rtde_spec.capture.reading.strides import EPB, count_cut_run, epb_run, same_run, strided
from rtde_spec.errors import UsageError

BLOCK = 8 << 20
LATEST_TIME = float(1 << 33)  # seconds: the year 2242; a later (or negative) capture time is damage
PCAPNG_SHB = 0x0A0D0D0A  # the same bytes in either byte order
PCAPNG_BYTE_ORDER = 0x1A2B3C4D
PCAP_MAGIC = {  # magic as read little-endian -> (byte order, seconds per timestamp unit)
    0xA1B2C3D4: ("<", 1e-6),
    0xA1B23C4D: ("<", 1e-9),
    0xD4C3B2A1: (">", 1e-6),
    0x4D3CB2A1: (">", 1e-9),
}
IDB, SPB = 1, 3  # pcapng block types read here (and EPB)
OTHER_FORMATS = {  # magic as read little-endian -> what the file is, for the error that refuses it
    0x34CDB2A1: ": a modified pcap, as a patched libpcap writes",
    0xA1B2CD34: ": a modified pcap, as a patched libpcap writes",
    0x55424D47: ": a Microsoft Network Monitor capture",
    0x6F6F6E73: ": a snoop capture",
}

Frame = tuple[float, int, bytes]  # (capture time, link type, frame bytes)


@dataclass
class Records:
    """One block of a capture file: where each whole frame starts, its length, time and link type."""

    buf: bytes | mmap.mmap  # offsets are into this
    upto: int  # the file position this block's records reach (for progress)
    offsets: Any  # numpy int64
    lengths: Any  # numpy int64
    times: Any  # numpy float64
    links: Any  # numpy int64


class _Columns:
    """The records of one block as they are found: strided runs, or one at a time."""

    def __init__(self) -> None:
        self.pieces: list[tuple[Any, Any, Any, Any]] = []

    def add(self, offsets: Any, lengths: Any, times: Any, link: int) -> None:
        import numpy as np

        self.pieces.append((offsets, lengths, times, np.full(len(offsets), link, dtype=np.int64)))

    def records(self, buf: bytes | mmap.mmap, upto: int, stats: dict[str, int]) -> Records | None:
        import numpy as np

        if not self.pieces:
            return None
        columns = (np.concatenate(column) for column in zip(*self.pieces, strict=True))
        offsets, lengths, times, links = columns
        bad = np.count_nonzero(~((times >= 0) & (times < LATEST_TIME)))  # NaN is not < either
        if bad:
            stats["bad_times"] = stats.get("bad_times", 0) + int(bad)
        return Records(
            buf, upto, offsets.astype(np.int64), lengths.astype(np.int64), times.astype(np.float64), links
        )


def blocks(f: IO[bytes], name: str, stats: dict[str, int], lag: int = 0) -> Iterator[Records]:
    """Every frame of the capture in file order, a block of the file at a time.

    `lag`: blocks of a mapped file kept mapped after they are handed on (a reader decoding
    views of them on other threads finds their pages still there; see `_by_block`)."""
    head = f.read(4)
    if len(head) < 4:
        raise UsageError("not a pcap or pcapng file (shorter than a header)", subject=f"file {name}")
    magic = int.from_bytes(head, "little")
    if magic == PCAPNG_SHB:
        yield from _pcapng(f, head, name, stats, lag)
    elif magic in PCAP_MAGIC:
        yield from _pcap(f, *PCAP_MAGIC[magic], name, stats, lag)
    else:
        from rtde_spec.output.ur_recordings import table_hint

        hint = table_hint(head + f.read(65536), name)
        if hint is not None:  # a table given for a capture: the command that reads it
            raise UsageError(f"not a capture: {hint}", subject=f"file {name}")
        other = OTHER_FORMATS.get(magic, "")
        raise UsageError(
            f"not a pcap or pcapng file (magic {head.hex()}{other}); a capture Wireshark opens converts "
            f"to pcapng with: editcap -F pcapng {name} {Path(name).stem}.pcapng",
            subject=f"file {name}",
        )


def frames(f: IO[bytes], name: str, stats: dict[str, int]) -> Iterator[Frame]:
    """Every frame of the capture in file order, one at a time."""
    for records in blocks(f, name, stats):
        buf = records.buf
        for off, length, ts, link in zip(
            records.offsets.tolist(),
            records.lengths.tolist(),
            records.times.tolist(),
            records.links.tolist(),
            strict=True,
        ):
            yield ts, link, buf[off : off + length]


Parse = Callable[[Any, int, int, _Columns], int]
Claim = Callable[[Any, int], int]  # the length the record header at a position claims (0: no header)


def _by_block(
    f: IO[bytes], carry: bytes, start: int, stats: dict[str, int], parse: Parse, claim: Claim, lag: int = 0
) -> Iterator[Records]:
    """The file a block at a time; `parse(buf, start, end, found)` finds the whole records in
    buf[start:end] and says where they end; the rest goes into the next block (or is
    counted as cut off at the end). `carry`: bytes already read, from file position `start`.
    The pages of a block done leave memory `lag` blocks later (their views stay valid either
    way: a page given back is read again from the file when touched)."""
    mapped = mapped_file(f)
    if mapped is None:
        yield from _read_blocks(f, carry, start, stats, parse, claim)
        return
    pos, size, window = start, len(mapped), BLOCK
    page = mmap.ALLOCATIONGRANULARITY
    done: list[int] = []  # where the blocks handed on start, oldest first (pages not yet given back)
    while pos < size:
        end = min(size, pos + window)
        if os.fstat(f.fileno()).st_size < end:  # reading a mapped page past the end would fault
            raise UsageError(
                f"the file got shorter while it was read (byte {end} of {size} is gone)",
                subject=f"file {getattr(f, 'name', '?')}",
            )
        populate(mapped, pos // page * page, end)
        found = _Columns()
        reached = parse(mapped, pos, end, found)
        records = found.records(mapped, reached, stats)
        if records is not None:
            yield records
        if reached == pos:  # no whole record in the window
            if end == size:
                break
            window *= 2  # a record larger than a block
            continue
        done.append(pos)
        if len(done) > lag:
            give_back(mapped, done.pop(0), reached if not done else done[0])
        pos, window = reached, BLOCK
    if pos < size:
        _stopped(stats, pos, size - pos, claimed=claim(mapped, pos))
    grown = os.fstat(f.fileno()).st_size - size
    if grown > 0:  # a capture still being written: read as it was when opened
        stats["grew_bytes"] = stats.get("grew_bytes", 0) + grown


def _stopped(stats: dict[str, int], at: int, unread: int, *, claimed: int = 0) -> None:
    """Reading ended `unread` bytes before the end of the file, at byte `at` (a cut-off record)."""
    stats["stopped_at"] = at
    stats["unread_bytes"] = unread
    stats["truncated"] = stats.get("truncated", 0) + 1
    stats["claimed"] = claimed


def _skipped(stats: dict[str, int], count: int) -> None:
    """`count` bytes from a record that cannot be one to the next whole record."""
    stats["bad_records"] = stats.get("bad_records", 0) + 1
    stats["skipped_file_bytes"] = stats.get("skipped_file_bytes", 0) + count


def _read_blocks(
    f: IO[bytes], carry: bytes, start: int, stats: dict[str, int], parse: Parse, claim: Claim
) -> Iterator[Records]:
    """`_by_block` for what cannot be mapped: read, and carry a cut-off record over.

    `read1` takes what a pipe has (up to a block) rather than waiting for a whole block,
    so a live capture piped in is decoded as it comes; while more is waiting, it is read
    on up to a block, from a pipe widened first (`pipes.py`). A record larger than what is
    held is waited for by doubling what is read before trying again, so a record
    claiming gigabytes costs reading the input once, not once per block.
    """
    read = getattr(f, "read1", f.read)
    widen(f, BLOCK)  # a pipe of 64 kB gave ~90 packages a block, each costing a block's set-up
    want = 0  # bytes to hold before parsing again (a large record is still coming)
    while True:
        pieces = [carry] if carry else []
        held = len(carry)
        chunk = b""
        while True:
            chunk = read(BLOCK)
            if chunk:
                pieces.append(chunk)
                held += len(chunk)
            if not chunk or (held >= want and (held >= BLOCK or not waiting(f))):
                break
        buf = b"".join(pieces) if len(pieces) != 1 else pieces[0]
        found = _Columns()
        pos = parse(buf, 0, len(buf), found)
        records = found.records(buf, start + pos, stats)
        if records is not None:
            yield records
        start += pos
        carry = buf[pos:]
        want = 2 * len(carry) if pos == 0 and len(carry) >= BLOCK else 0
        if not chunk:
            if carry:
                _stopped(stats, start, len(carry), claimed=claim(carry, 0))
            return


def _pcap(
    f: IO[bytes], order: str, unit: float, name: str, stats: dict[str, int], lag: int = 0
) -> Iterator[Records]:
    import numpy as np

    rest = f.read(20)
    if len(rest) < 20:
        raise UsageError("not a pcap file (its header is cut off)", subject=f"file {name}")
    linktype = struct.unpack(order + "I", rest[16:20])[0] & 0xFFFF  # upper 16 bits: FCS length, flags
    size_at = struct.Struct(order + "I").unpack_from  # a record header's captured length, at +8
    u32 = np.dtype(order + "u4")
    snaplen = struct.unpack(order + "I", rest[12:16])[0]
    limit = pcap_limit(snaplen)  # from the snap length
    snap_length(stats, snaplen)
    fractions = 1_000_000 if unit == 1e-6 else 1_000_000_000
    last_secs: list[int] = []  # of the last whole record: where to look after damage

    def parse(buf: Any, pos: int, end: int, found: _Columns) -> int:
        while pos + 16 <= end:
            (caplen,) = size_at(buf, pos + 8)
            if caplen > limit:  # no record is this long: go on at the next whole one
                near = last_secs[-1] if last_secs else None
                after = next_pcap_record(buf, pos + 1, end, order, limit, fractions, near)
                resume = end - 15 if after is None else after
                _skipped(stats, resume - pos)
                pos = resume
                continue
            stride = 16 + caplen
            if pos + stride > end:
                break
            if caplen and pos + stride + 16 <= end and size_at(buf, pos + stride + 8)[0] != caplen:
                file, other = (u32, fractions, linktype), size_at(buf, pos + stride + 8)[0]
                sizes = (caplen, other if other <= limit else 0)  # sizes vary (data and ACK frames):
                got = pcap_pairs(found, stats, buf, pos, end, sizes, file)  # in turns, or one by one
                pos, last = got or pcap_walked(found, stats, buf, pos, end, limit, size_at, file)
                last_secs[:] = [last]
                continue
            same = same_run(buf, pos, stride, (end - pos) // stride, 8, caplen, u32)
            if not caplen:  # no frame in them (a zero-filled stretch of the file reads as these)
                stats["empty_records"] = stats.get("empty_records", 0) + same
                pos += same * stride
                continue
            secs, fracs = (strided(buf, pos + at, stride, same, u32) for at in (0, 4))
            starts = pos + 16 + np.arange(same, dtype=np.int64) * stride
            lengths = np.full(same, caplen, dtype=np.int64)
            times = secs + fracs / fractions  # the fraction's nearest float, then the sum's
            found.add(starts, lengths, times, linktype)
            count_cut_run(stats, buf, pos + 12, stride, same, lengths, u32, times)
            last_secs[:] = [int(secs[-1])]
            pos += same * stride
        return pos

    def claim(buf: Any, pos: int) -> int:
        return int(size_at(buf, pos + 8)[0]) + 16 if len(buf) - pos >= 16 else 0

    yield from _by_block(f, b"", 24, stats, parse, claim, lag)  # after the file header


def _pcapng(f: IO[bytes], first: bytes, name: str, stats: dict[str, int], lag: int = 0) -> Iterator[Records]:
    import numpy as np

    order = "<"
    interfaces: list[tuple[int, float, int]] = []  # (link type, seconds per timestamp unit, offset)

    def parse(buf: Any, pos: int, end: int, found: _Columns) -> int:
        nonlocal order, interfaces
        while pos + 12 <= end:
            if int.from_bytes(buf[pos : pos + 4], "little") == PCAPNG_SHB:  # a new section
                magic = int.from_bytes(buf[pos + 8 : pos + 12], "little")
                order = "<" if magic == PCAPNG_BYTE_ORDER else ">"
                interfaces = []
            btype, length = struct.unpack_from(order + "II", buf, pos)
            if (
                length < 12
                or length % 4
                or length > MAX_BLOCK
                or (
                    pos + length <= end
                    and struct.unpack_from(order + "I", buf, pos + length - 4)[0] != length
                )
            ):  # no block: go on at the next whole one
                after = next_pcapng_block(buf, pos + 4, end, order)
                resume = pos + 4 + (max(0, end - 11 - pos - 4) + 3) // 4 * 4 if after is None else after
                _skipped(stats, resume - pos)
                pos = resume
                continue
            if pos + length > end:
                break
            if btype == EPB and length >= 32 and next_differs(buf, pos + length, end, order, length):
                pos = pcapng_mixed(found, stats, buf, pos, end, order, interfaces)  # data and ACKs
                continue
            if btype == EPB and length >= 32:
                u32 = np.dtype(order + "u4")
                iface = struct.unpack_from(order + "I", buf, pos + 8)[0]
                same = epb_run(buf, pos, length, end, u32, iface)
                linktype, unit, shift = interfaces[iface] if iface < len(interfaces) else (-1, 1e-6, 0)
                high, low, caplen = (strided(buf, pos + at, length, same, u32) for at in (12, 16, 20))
                starts = pos + 28 + np.arange(same, dtype=np.int64) * length
                lengths = np.minimum(caplen, length - 32)
                times = seconds((high << 32) | low, unit, shift)
                found.add(starts, lengths, times, linktype)
                count_cut_run(stats, buf, pos + 24, length, same, lengths, u32, times)
                pos += same * length
                continue
            if btype == IDB:
                interfaces.append(interface(buf, pos, length, order, stats))
            elif btype == SPB and interfaces:  # no time, interface 0, cut at the snap length
                (origlen,) = struct.unpack_from(order + "I", buf, pos + 8)
                size = np.array([max(0, min(origlen, length - 16))])
                found.add(np.array([pos + 12]), size, np.array([0.0]), interfaces[0][0])
                count_cut(stats, size, np.array([origlen]))
            pos += length
        return pos

    def claim(buf: Any, pos: int) -> int:
        return int(struct.unpack_from(order + "I", buf, pos + 4)[0]) if len(buf) - pos >= 8 else 0

    yield from _by_block(f, first, 0, stats, parse, claim, lag)
