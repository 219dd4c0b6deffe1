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


def fragment6(ident: int, offset: int, more: bool, payload: bytes) -> bytes:
    """An IPv6 header (RFC 8200 section 3) and a fragment header (section 4.5: next header TCP,
    offset in 8-byte units with M in its lowest bit, identification)."""
    source, destination = b"\xfd" + b"\0" * 14 + b"\1", b"\xfd" + b"\0" * 14 + b"\2"
    header = struct.pack(">IHBB16s16s", 6 << 28, 8 + len(payload), 44, 64, source, destination)
    return ETHERNET[:12] + b"\x86\xdd" + header + struct.pack(">BBHI", 6, 0, offset | more, ident) + payload


def test_ipv6_fragments_share_the_ipv4_bounds_each_looked_at_once() -> None:
    """IPv6 fragments (put back together as IPv4's are) cost their number too, with the same rules:
    a copy of a fragment of a packet just put back together is counted as a copy."""
    count = 8000
    order = [0, count - 1, *range(1, count - 2)]
    frames = [fragment6(7, k * 8, k != count - 1, bytes([k % 251]) * 8) for k in order]
    counts: dict[str, int] = {}
    fragments = Fragments(counts)
    started = time.process_time()
    assert all(fragments.add_v6(frame, 14, 54) is None for frame in frames)
    elapsed = time.process_time() - started
    last = fragment6(7, (count - 2) * 8, True, bytes([(count - 2) % 251]) * 8)
    whole = fragments.add_v6(last, 14, 54)
    assert whole is not None and whole[12:14] == b"\x86\xdd" and whole[20] == 6  # next header: TCP
    assert whole[54:] == b"".join(bytes([k % 251]) * 8 for k in range(count))
    assert int.from_bytes(whole[18:20], "big") == count * 8  # its payload length
    assert fragments.add_v6(last, 14, 54) is None  # the same frame again: a copy
    assert counts == {"ip_fragments": count + 1, "ip_reassembled": 1, "ip_fragment_copies": 1}
    assert elapsed < 1.0, f"{elapsed:.2f} s for {count} fragments"


def test_fragments_of_a_datagram_never_completed_expire_before_its_id_comes_again() -> None:
    """A datagram whose last fragment was lost waited for ever (only 1,024 others pushed it out):
    when its id came again (the 16-bit id wraps after 65,536 datagrams of a host), the new
    datagram was put together with the stale fragment's bytes, and came out longer than it was.
    A receiver drops fragments it held past its reassembly time-out (Linux's ipfrag_time: 30 s;
    RFC 8200 section 4.5 for IPv6: 60 s); so does the reader, counting them as lost."""
    counts: dict[str, int] = {}
    fragments = Fragments(counts)
    fragments.now = 1000.0
    assert fragments.add(fragment(7, 8, True, b"s" * 24), 14) is None  # its other fragments never come
    fragments.now = 1100.0  # the id again, 100 s later
    assert fragments.add(fragment(7, 0, True, b"n" * 16), 14) is None
    whole = fragments.add(fragment(7, 16, False, b"m" * 8), 14)
    assert whole is not None and whole[34:] == b"n" * 16 + b"m" * 8
    assert counts["ip_fragments_lost"] == 1 and counts["ip_fragments_expired"] == 1
    from rtde_spec.capture.tables.summary import CaptureSummary

    assert CaptureSummary("x.pcap", 3, reading=counts).damage() == [
        "1 IP fragments of datagrams whose other fragments never came (skipped); 1 of those datagrams "
        "waited past the reassembly time-out (30 s for IPv4, 60 s for IPv6, as Linux holds them): a "
        "later datagram of the same id is not mixed with them"
    ]
