"""Capture records of varied sizes, walked one at a time and their headers read together.

A capture taken on either host of a 500 Hz stream has the peer's ACK (a 66-byte frame) after
nearly every data package, so record sizes alternate and the strided reading
(`strides.py`, runs of one size) found runs of one record: ~10 numpy calls per record, a
capture 10x slower than one without the ACKs. Here the walk is one `struct` read per
record, and the headers of all the records walked are read in a few numpy calls.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from rtde_spec.capture.reading.headers import count_cut, seconds
from rtde_spec.capture.reading.strides import EPB, epb_run, same_run, strided

RUN_MIN = 16  # records of one size in a row: the walk stops before them, the strided reading takes them
SizeAt = Callable[[Any, int], tuple[int, ...]]


def walk_pcap(buf: Any, pos: int, end: int, limit: int, size_at: SizeAt) -> tuple[int, list[int]]:
    """Starts of the pcap records from `pos` on, while each is whole, holds a frame of at most
    `limit` bytes and no RUN_MIN in a row have one size; and where the walk stopped."""
    starts: list[int] = []
    append = starts.append
    last = same = 0
    while pos + 16 <= end:
        (caplen,) = size_at(buf, pos + 8)
        if not caplen or caplen > limit or pos + 16 + caplen > end:
            break
        same = same + 1 if caplen == last else 1
        last = caplen
        if same >= RUN_MIN:  # a run of one size begins: from its first record on, read strided
            del starts[len(starts) - (RUN_MIN - 1) :]
            pos -= (RUN_MIN - 1) * (16 + caplen)
            break
        append(pos)
        pos += 16 + caplen
    return pos, starts


def walk_pcapng(
    buf: Any, pos: int, end: int, order: str, epb: int, max_block: int
) -> tuple[int, list[int], int]:
    """Starts of the Enhanced Packet Blocks from `pos` on, of one interface, while each is whole
    and well formed and no RUN_MIN in a row have one length; where the walk stopped, and the
    interface. Any other block, or a doubtful one, ends the walk: the block reader looks at it."""
    head = struct.Struct(order + "III").unpack_from  # block type, length, interface
    tail = struct.Struct(order + "I").unpack_from
    starts: list[int] = []
    append = starts.append
    iface = -1
    last = same = 0
    while pos + 12 <= end:
        btype, length, this = head(buf, pos)
        if (
            btype != epb
            or length < 32
            or length % 4
            or length > max_block
            or pos + length > end
            or tail(buf, pos + length - 4)[0] != length
            or (starts and this != iface)
        ):
            break
        iface = this
        same = same + 1 if length == last else 1
        last = length
        if same >= RUN_MIN:
            del starts[len(starts) - (RUN_MIN - 1) :]
            pos -= (RUN_MIN - 1) * length
            break
        append(pos)
        pos += length
    return pos, starts, iface


def fields_at(buf: Any, starts: list[int], offsets: tuple[int, ...], u32: Any) -> list[Any]:
    """The 32-bit header fields at `offsets` from each start, as int64 columns: one gather of
    the header bytes, one view."""
    import numpy as np

    u8 = np.frombuffer(buf, dtype=np.uint8)
    span = max(offsets) + 4
    rows = u8[np.asarray(starts, dtype=np.int64)[:, None] + np.arange(span)]  # (records, span) bytes
    words = [rows[:, at : at + 4].copy().view(u32)[:, 0].astype(np.int64) for at in offsets]
    return words


def pcap_walked(
    found: Any, stats: dict[str, int], buf: Any, pos: int, end: int, limit: int, size_at: SizeAt, file: Any
) -> tuple[int, int]:
    """The pcap records walked from `pos` (the first is whole and of another size than the next)
    added to `found` (`file`: byte order, fractions per second, link type); where the walk
    stopped and the whole seconds of the last record."""
    import numpy as np

    u32, fractions, linktype = file
    pos, starts = walk_pcap(buf, pos, end, limit, size_at)
    secs, fracs, lengths, originals = fields_at(buf, starts, (0, 4, 8, 12), u32)
    times = secs + fracs / fractions  # as the strided reading computes them
    found.add(np.asarray(starts, dtype=np.int64) + 16, lengths, times, linktype)
    count_cut(stats, lengths, originals, times)
    return pos, int(secs[-1])


def pcapng_walked(
    found: Any, stats: dict[str, int], buf: Any, pos: int, end: int, order: str, interfaces: list[Any]
) -> int:
    """The Enhanced Packet Blocks walked from `pos` added to `found`; where the walk stopped."""
    import numpy as np

    from rtde_spec.capture.reading.recordsync import MAX_BLOCK

    pos, starts, iface = walk_pcapng(buf, pos, end, order, EPB, MAX_BLOCK)
    linktype, unit, shift = interfaces[iface] if iface < len(interfaces) else (-1, 1e-6, 0)
    length, high, low, caplen, original = fields_at(buf, starts, (4, 12, 16, 20, 24), np.dtype(order + "u4"))
    lengths = np.minimum(caplen, length - 32)
    times = seconds((high << 32) | low, unit, shift)
    found.add(np.asarray(starts, dtype=np.int64) + 28, lengths, times, linktype)
    count_cut(stats, lengths, original, times)
    return pos


def next_differs(buf: Any, pos: int, end: int, order: str, length: int) -> bool:
    """Whether a pcapng block starts at `pos` in this block of the file with another length."""
    return pos + 8 <= end and struct.unpack_from(order + "I", buf, pos + 4)[0] != length


def pcap_pairs(
    found: Any, stats: dict[str, int], buf: Any, pos: int, end: int, sizes: tuple[int, int], file: Any
) -> tuple[int, int] | None:
    """Records of two sizes taking turns (each package, then the peer's ACK: most of a real
    capture) read as one strided run of pairs; where they stop and the last one's whole seconds,
    or None when fewer than RUN_MIN pairs follow (they are walked)."""
    import numpy as np

    u32, fractions, linktype = file
    if not all(sizes):  # no frame in the second record, or more than the snap length allows
        return None
    one = 16 + sizes[0]
    pair = one + 16 + sizes[1]
    count = same_run(buf, pos, pair, (end - pos) // pair, 8, sizes[0], u32)
    if count >= RUN_MIN:
        count = min(count, same_run(buf, pos + one, pair, count, 8, sizes[1], u32))
    if count < RUN_MIN:
        return None
    both = np.empty((4, count, 2), dtype=np.int64)  # secs, fractions, originals, starts; each pair's two
    for side, at in enumerate((pos, pos + one)):
        for row, field in enumerate((0, 4, 12)):
            both[row, :, side] = strided(buf, at + field, pair, count, u32)
        both[3, :, side] = at + 16 + np.arange(count, dtype=np.int64) * pair
    secs, fracs, originals, starts = (column.reshape(-1) for column in both)
    lengths = np.tile(np.array(sizes, dtype=np.int64), count)
    times = secs + fracs / fractions
    found.add(starts, lengths, times, linktype)
    count_cut(stats, lengths, originals, times)
    return pos + count * pair, int(secs[-1])


def pcapng_pairs(
    found: Any, stats: dict[str, int], buf: Any, pos: int, end: int, order: str, interfaces: list[Any]
) -> int | None:
    """Enhanced Packet Blocks of two lengths taking turns (a package, then the peer's ACK), of one
    interface, read as one strided run of pairs; where they stop, or None when fewer than
    RUN_MIN pairs follow (they are walked)."""
    import numpy as np

    u32 = np.dtype(order + "u4")
    head = struct.Struct(order + "III")
    _, first, iface = head.unpack_from(buf, pos)
    if pos + first + 12 > end:
        return None
    kind, second, other = head.unpack_from(buf, pos + first)
    if kind != EPB or other != iface or second < 32 or second % 4:
        return None
    pair = first + second
    count = epb_run(buf, pos, first, end, u32, iface, pair)
    if count >= RUN_MIN:
        count = min(count, epb_run(buf, pos + first, second, end - first, u32, iface, pair))
    if count < RUN_MIN:
        return None
    linktype, unit, shift = interfaces[iface] if iface < len(interfaces) else (-1, 1e-6, 0)
    both = np.empty((5, count, 2), dtype=np.int64)  # high, low, caplen, original, start; each pair's two
    for side, (at, length) in enumerate(((pos, first), (pos + first, second))):
        for row, field in enumerate((12, 16, 20, 24)):
            both[row, :, side] = strided(buf, at + field, pair, count, u32)
        both[2, :, side] = np.minimum(both[2, :, side], length - 32)
        both[4, :, side] = at + 28 + np.arange(count, dtype=np.int64) * pair
    high, low, lengths, originals, starts = (column.reshape(-1) for column in both)
    times = seconds((high << 32) | low, unit, shift)
    found.add(starts, lengths, times, linktype)
    count_cut(stats, lengths, originals, times)
    return pos + count * pair


def pcapng_mixed(
    found: Any, stats: dict[str, int], buf: Any, pos: int, end: int, order: str, interfaces: list[Any]
) -> int:
    """Enhanced Packet Blocks of varied lengths from `pos` (the first of another length than the
    next) added to `found`: in pairs where two lengths take turns, else walked; where they stop."""
    paired = pcapng_pairs(found, stats, buf, pos, end, order, interfaces)
    return paired if paired is not None else pcapng_walked(found, stats, buf, pos, end, order, interfaces)
