"""Text lines in a capture (the dashboard server, the script sender) framed alike however TCP
cut them into segments."""

from __future__ import annotations

import pytest

from rtde_spec.capture.framing.lines import LineFraming
from rtde_spec.capture.tcp import Chunk

LIMIT = 4096


def framed(data: bytes, piece: int) -> tuple[list[bytes], int, int]:
    lines = LineFraming(LIMIT)
    out = [line for i in range(0, len(data), piece) for line in lines.feed(Chunk(0.0, data[i : i + piece]))]
    return out + lines.finish(), lines.too_long, lines.skipped


@pytest.mark.parametrize("piece", [1, 7, 1460, 100_000])
def test_a_line_over_the_limit_is_dropped_whole_or_in_segments(piece: int) -> None:
    """A 5,009-byte line was kept when it came in one segment and dropped (its reply then filed
    as unrequested) when it came in 1,460-byte ones."""
    long = b"load " + b"a" * 5000 + b".urp"
    data = b"play\n" + long + b"\nstop\r\n" + b"x" * (LIMIT + 1) + b"\n" + b"y" * LIMIT + b"\npause"
    lines, too_long, skipped = framed(data, piece)
    assert lines == [b"play", b"stop", b"y" * LIMIT, b"pause"]
    assert (too_long, skipped) == (2, len(long) + 1 + LIMIT + 2)
