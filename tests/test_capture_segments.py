"""A capture decodes alike however TCP cut the same bytes into segments: text lines (the
dashboard server, the script sender) and the capture time of retransmitted bytes."""

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


@pytest.mark.parametrize("split", [False, True])
def test_bytes_keep_the_time_they_first_arrived_when_a_longer_retransmission_comes(split: bool) -> None:
    """Behind a hole, b"x\\nstop\\n" at t=1.0 (one segment, or two), then retransmitted whole at
    t=1.5: the longer copy replaced the shorter held one with its own time, so "stop" was at 1.5
    when the first copy came in two segments and at 1.0 when it came in one."""
    from rtde_spec.capture.tcp import Direction

    tcp = Direction()
    tcp.feed(0.0, 999, b"", syn=True)
    data = b"x\nstop\n"
    pieces = [(1005, data[:3]), (1008, data[3:])] if split else [(1005, data)]
    for seq, piece in pieces:
        assert tcp.feed(1.0, seq, piece) == []  # behind the hole of bytes 1000..1004
    assert tcp.feed(1.5, 1005, data) == []
    chunks = tcp.feed(2.0, 1000, b"play\n")
    assert b"".join(c.data for c in chunks) == b"play\n" + data
    assert [c.time for c in chunks if c.data != b"play\n"] == [1.0] * len(pieces)
    assert tcp.conflicts == 0


@pytest.mark.parametrize("first", [1000, 20_000, 70_000])
def test_a_copy_is_compared_with_the_bytes_it_is_a_copy_of_after_a_segment_of_any_size(first: int) -> None:
    """The last delivered bytes are kept to compare copies with. A segment longer than what is
    kept (segmentation offload: 64 kB) kept its last 16 kB behind the older ones, as if they
    followed each other: an equal copy of bytes before it counted as a conflict."""
    from rtde_spec.capture.tcp import RECENT, Direction

    stream = bytes(range(256)) * 400  # 102,400 bytes, no two 16 kB stretches alike
    tcp = Direction()
    tcp.feed(0.0, 999, b"", syn=True)
    delivered = tcp.feed(1.0, 1000, stream[:first]) + tcp.feed(1.1, 1000 + first, stream[first:])
    assert b"".join(c.data for c in delivered) == stream
    for back in (100, RECENT - 100, RECENT + 100):  # equal copies of bytes still kept or not
        start = len(stream) - back
        tcp.feed(1.2, 1000 + start, stream[start : start + 50])
    assert (tcp.conflicts, tcp.copies) == (0, 3)
    tcp.feed(1.3, 1000 + len(stream) - 100, b"\xff" * 50)  # a copy that differs: a conflict
    assert (tcp.conflicts, tcp.conflict_bytes) == (1, 50)


def test_the_bytes_kept_after_a_run_are_those_kept_after_its_packages_one_by_one() -> None:
    """A run of whole packages is delivered at once (`advance`): what it keeps to compare copies
    with is what delivering its packages one by one keeps (between 16 and 32 kB)."""
    from rtde_spec.capture.tcp import Direction

    size, count = 64, 1000
    stream = b"".join(i.to_bytes(4, "big") * (size // 4) for i in range(count + 300))
    for before in (0, 3, 300):  # packages delivered one by one before the run
        one, run = Direction(), Direction()
        for tcp in (one, run):
            tcp.feed(0.0, 999, b"", syn=True)
            for i in range(before):
                tcp.feed(1.0, 1000 + i * size, stream[i * size : (i + 1) * size])
        for i in range(before, before + count):
            one.feed(1.0, 1000 + i * size, stream[i * size : (i + 1) * size])
        run.advance(count * size, stream[before * size : (before + count) * size], size)
        assert (run.pos, bytes(run._recent)) == (one.pos, bytes(one._recent)), before
