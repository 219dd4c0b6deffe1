"""Runs of capture records of one size, read through strided numpy views of their headers.

A steady stream (records of one size in a row) is most of a capture; reading its record
headers as strided columns costs no Python step per record.
"""

from __future__ import annotations

import struct
from typing import Any

from rtde_spec.capture.reading.headers import count_cut

EPB = 6  # pcapng's Enhanced Packet Block


def count_cut_run(
    stats: dict[str, int], buf: Any, at: int, stride: int, same: int, lengths: Any, u32: Any, times: Any
) -> None:
    """Records of a run that a snap length cut (their original length, at `at`, over what the
    file holds; `times` their capture times). A run of one record (data and ACK frames alternate:
    most of a real session's) is one `struct` read, not numpy calls."""
    if same > 1:
        count_cut(stats, lengths, strided(buf, at, stride, same, u32), times)
        return
    original = struct.unpack_from(u32.str[0] + "I", buf, at)[0]  # the byte order of the file
    if original > int(lengths[0]):
        import numpy as np

        count_cut(stats, lengths, np.array([original]), times)


def strided(buf: Any, start: int, stride: int, count: int, dtype: Any) -> Any:
    """`count` values of `dtype` at `start`, `start + stride`, ... as int64."""
    import numpy as np

    return np.ndarray((count,), dtype=dtype, buffer=buf, offset=start, strides=(stride,)).astype(np.int64)


def same_run(buf: Any, pos: int, stride: int, count: int, at: int, value: int, dtype: Any) -> int:
    """How many records of `stride` bytes from `pos` on hold `value` at offset `at` (at least 1).

    Looked at in windows growing 4x (16, 64, 256, ...), so finding a run costs its length,
    not the rest of the block: short runs of many sizes (many small connections) stay linear."""
    if count <= 1:
        return 1
    done, window = 0, 16
    while done < count:
        n = min(window, count - done)
        differs = strided(buf, pos + done * stride + at, stride, n, dtype) != value
        if differs.any():
            return max(1, done + int(differs.argmax()))
        done += n
        window *= 4
    return count


def epb_run(buf: Any, pos: int, length: int, end: int, u32: Any, iface: int, every: int = 0) -> int:
    """How many pcapng Enhanced Packet Blocks of `length` bytes, `every` bytes apart (0: one after
    the other) from `pos` on, are alike: the same length at both ends, the same block type and
    interface (at least 1)."""
    stride = every or length
    same = same_run(buf, pos, stride, (end - pos) // stride, 4, length, u32)
    same = min(same, same_run(buf, pos, stride, same, length - 4, length, u32))  # its end
    same = min(same, same_run(buf, pos, stride, same, 0, EPB, u32))
    return min(same, same_run(buf, pos, stride, same, 8, iface, u32))
