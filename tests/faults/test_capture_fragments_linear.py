"""IPv4 fragments of one datagram are each looked at once, whatever order they come in.

Every fragment sorted and walked all the fragments of its datagram held so far to see
whether it was whole: a datagram of 8,000 8-byte fragments whose second-to-last never
comes took 9.5 s (the square of the fragments; a datagram may have 8,192)."""

from __future__ import annotations

import struct
import time

from rtde_spec.capture.reading.ipfrag import Fragments

ETHERNET = b"\x04" * 6 + b"\x02" * 6 + b"\x08\x00"


def fragment(ident: int, offset: int, more: bool, payload: bytes) -> bytes:
    flags = (0x2000 if more else 0) | offset // 8
    header = struct.pack(
        ">BBHHHBBH4s4s", 0x45, 0, 20 + len(payload), ident, flags, 64, 6, 0, b"\n\0\0\n", b"\n\0\0\2"
    )
    return ETHERNET + header + payload


def test_a_datagram_of_thousands_of_fragments_costs_their_number() -> None:
    count = 8000
    order = [0, count - 1, *range(1, count - 2)]  # the one before the last comes at the very end
    frames = [fragment(7, k * 8, k != count - 1, bytes([k % 251]) * 8) for k in order]
    last = fragment(7, (count - 2) * 8, True, bytes([(count - 2) % 251]) * 8)
    counts: dict[str, int] = {}
    fragments = Fragments(counts)
    started = time.process_time()
    assert all(fragments.add(frame, 14) is None for frame in frames)
    elapsed = time.process_time() - started
    whole = fragments.add(last, 14)
    assert whole is not None and whole[34:] == b"".join(bytes([k % 251]) * 8 for k in range(count))
    assert counts == {"ip_fragments": count, "ip_reassembled": 1}
    assert elapsed < 1.0, f"{elapsed:.2f} s for {count} fragments"


def test_a_copy_of_a_fragment_replaces_it_and_a_shorter_copy_is_counted_again() -> None:
    """The bytes reached are kept as fragments come; a copy of one held (another capture point, a
    datagram id used again) replaces it, as before: a shorter one leaves a hole to fill."""
    fragments = Fragments({})
    assert fragments.add(fragment(9, 0, True, b"a" * 16), 14) is None
    assert fragments.add(fragment(9, 0, True, b"b" * 8), 14) is None  # shorter: bytes 8..15 missing
    assert fragments.add(fragment(9, 16, False, b"c" * 8), 14) is None
    whole = fragments.add(fragment(9, 8, True, b"d" * 8), 14)
    assert whole is not None and whole[34:] == b"b" * 8 + b"d" * 8 + b"c" * 8
