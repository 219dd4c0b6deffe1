"""What a capture file's headers say about its frames: each interface's link type and time
resolution (pcapng), the snap length, and the frames that snap length cut.

A capture taken with a snap length (`tcpdump -s 80`, `dumpcap -s 80`) keeps only the first
bytes of each frame; its record says how long the frame was. Decoded as it is, the rest of
each TCP payload reads as lost segments and a setup exchange never seen; the counts here let
the summary say what happened and how to capture instead (`-s 0`).
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from typing import Any


def snap_length(stats: dict[str, int], snaplen: int) -> None:
    """The smallest snap length the file's header (or an interface) declares; 0: none."""
    if snaplen and (not stats.get("snaplen") or snaplen < stats["snaplen"]):
        stats["snaplen"] = snaplen


def count_cut(stats: dict[str, int], lengths: Any, origs: Any, times: Any = None) -> None:
    """Records that hold less of their frame than it had (orig_len > incl_len): a snap length cut
    them, and the rest of their TCP payload is not in the file. Counted, with where they end and
    the capture times of the first and last (microseconds, `cut_first_us`, `cut_last_us`), so the
    summary names the cause and where in the capture rather than only the gaps it leaves."""
    cut = origs > lengths
    if not cut.any():
        return
    kept = lengths[cut]
    stats["cut_frames"] = stats.get("cut_frames", 0) + int(cut.sum())
    low, high = int(kept.min()), int(kept.max())
    stats["cut_at_min"] = min(stats.get("cut_at_min", low), low)
    stats["cut_at_max"] = max(stats.get("cut_at_max", high), high)
    if times is not None:
        when = times[cut]
        try:  # a time that is no number (a damaged record) leaves the times out
            stats.setdefault("cut_first_us", round(float(when[0]) * 1e6))
            stats["cut_last_us"] = round(float(when[-1]) * 1e6)
        except (ValueError, OverflowError):
            pass


def interface(buf: Any, pos: int, length: int, order: str, stats: dict[str, int]) -> tuple[int, float, int]:
    """(link type, seconds per timestamp unit, seconds to add) of an interface block; its snap
    length to `stats`."""
    if length >= 20:  # a whole interface block: its snap length at +12
        snap_length(stats, struct.unpack_from(order + "I", buf, pos + 12)[0])
    linktype = struct.unpack_from(order + "H", buf, pos + 8)[0]
    options = buf[pos + 16 : pos + length - 4]
    return linktype, resolution(options, order), time_offset(options, order)


def _options(options: bytes, order: str) -> Iterator[tuple[int, bytes]]:
    """(code, value) of each option up to opt_endofopt; a value cut short by the block is as held."""
    pos = 0
    while pos + 4 <= len(options):
        code, size = struct.unpack(order + "HH", options[pos : pos + 4])
        if code == 0:
            return
        yield code, options[pos + 4 : pos + 4 + size]
        pos += 4 + size + (-size % 4)


def seconds(ticks: Any, unit: float, shift: int = 0) -> Any:
    """Capture times in seconds (numpy float64) of timestamps counted in `unit`s, plus `shift`
    seconds; each the float64 nearest the exact time, as a pcap's seconds and fraction give it.
    Whole seconds and the fraction are taken apart in integers first: `ticks * unit` rounded a
    nanosecond count past 2**53 before scaling it, so 2,360 of 4,949 frames of a dumpcap capture
    (if_tsresol 9) came out a float step (238 ns) off the time in the file, and off the same
    frames read from a nanosecond pcap (`editcap -F nsecpcap`)."""
    import numpy as np

    per = round(1 / unit) if 0 < unit <= 1 else 0  # units per second: 10**n or 2**n
    if not per or per > 1 << 53 or abs(per * unit - 1) > 1e-9:
        return ticks * unit + shift
    whole, part = np.divmod(ticks, per)
    return (whole + shift).astype(np.float64) + part / per


def resolution(options: bytes, order: str) -> float:
    """Seconds per timestamp unit from an interface's if_tsresol option (default microseconds)."""
    for code, value in _options(options, order):
        if code == 9 and value:  # its value byte, if the block holds it
            return 2.0 ** -(value[0] & 0x7F) if value[0] & 0x80 else 10.0 ** -value[0]
    return 1e-6


def time_offset(options: bytes, order: str) -> int:
    """Seconds to add to an interface's timestamps, from its if_tsoffset option (pcapng: "an offset
    (in seconds) that must be added to the timestamp of each packet"; default 0)."""
    for code, value in _options(options, order):
        if code == 14 and len(value) >= 8:
            return int(struct.unpack(order + "q", value[:8])[0])
    return 0
