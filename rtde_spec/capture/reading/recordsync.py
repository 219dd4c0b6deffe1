"""The next whole record after a damaged one in a pcap or pcapng file (the packets layer's resync).

A record header whose length cannot be (more than any snap length, not a pcapng block
size, a block whose trailing length differs) would end reading there and lose the rest
of the file. Instead the bytes after it are searched for a header that can be one and
that the next header (pcap) or its own trailing length (pcapng) confirms; reading goes
on from there, and the bytes passed over are counted.
"""

from __future__ import annotations

import re
import struct
from typing import Any

MAX_PCAP_RECORD = 1 << 18  # libpcap's largest snap length: the limit when the file's own is unusable
MAX_BLOCK = 1 << 24  # a pcapng block longer than this is taken for damage
PCAPNG_BLOCK_TYPES = {1, 2, 3, 4, 5, 6, 9, 10, 0x0A0D0D0A, 0x00000BAD, 0x40000BAD}


def pcap_limit(snaplen: int) -> int:
    """The longest record taken as one: the file's snap length, but never less than libpcap's
    largest (writers such as dpkt put 1500 there and write longer records all the same)."""
    return max(MAX_PCAP_RECORD, snaplen if snaplen <= 1 << 24 else 0)


NEAR = 86_400  # seconds: a record found after damage is within a day of the last whole one


def next_pcap_record(
    buf: Any, start: int, end: int, order: str, limit: int, frac_limit: int, near: int | None
) -> int | None:
    """The first position from `start` (before `end`) of a record header that can be one and is
    followed by another (or reaches `end` exactly); failing that, the first that reaches past
    `end` (it cannot be told yet). A header that can be one: lengths up to `limit`, the
    captured one not over the original, the fraction of a second under `frac_limit`, the
    seconds within NEAR of `near` (the last whole record's)."""
    header = struct.Struct(order + "IIII")

    def after(at: int) -> int | None:
        secs, frac, caplen, origlen = header.unpack_from(buf, at)
        if caplen > limit or frac >= frac_limit or not caplen <= origlen <= limit:
            return None
        if near is not None and abs(secs - near) > NEAR:
            return None
        return at + 16 + caplen

    untold = None
    for at in range(start, end - 15):
        following = after(at)
        if following is None:
            continue
        if following == end or (following + 16 <= end and after(following) is not None):
            return at
        if following + 16 > end and untold is None:
            untold = at
    return untold


def block_fits(buf: Any, at: int, end: int, order: str) -> bool | None:
    """Whether the pcapng block at `at` is one: a known type, a length it can have and the same
    length at its end; None when its end is past `end` (cannot be told yet)."""
    btype, length = struct.unpack_from(order + "II", buf, at)
    if length < 12 or length % 4 or length > MAX_BLOCK or btype not in PCAPNG_BLOCK_TYPES:
        return False
    if at + length > end:
        return None
    return bool(struct.unpack_from(order + "I", buf, at + length - 4)[0] == length)


def next_pcapng_block(buf: Any, start: int, end: int, order: str) -> int | None:
    """The first 4-aligned position from `start` of a block `block_fits` does not refuse.

    No block type is 0: a stretch of zeros (a preallocated file's unwritten end) is passed in
    one C search for its end, not looked at a word at a time."""
    at = start
    while at <= end - 12:
        if not _WORD.unpack_from(buf, at)[0]:
            nonzero = _NONZERO.search(buf, at, end)
            if nonzero is None:
                return None
            at += (nonzero.start() - at) // 4 * 4  # the word holding it, on the blocks' alignment
            if at > end - 12:
                return None
        if block_fits(buf, at, end, order) is not False:
            return at
        at += 4
    return None


_WORD = struct.Struct("I")  # a zero word reads as zero in either byte order
_NONZERO = re.compile(rb"[^\x00]")
