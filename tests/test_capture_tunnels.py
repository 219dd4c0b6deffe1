"""Robot traffic as a collector captures it: a switch port mirrored over ERSPAN, an overlay
network (VXLAN, Geneve), GRE and IP-in-IP tunnels, MPLS, a MikroTik's sniffer stream (TZSP),
Linux's NFLOG, IPv6 fragments. Each decodes to the rows of the same frames captured directly; a
damaged tunnel header costs its own frame, reported with its number. The headers are built here
with struct, each laid out as the specification cited beside it says (dpkt, the tests' writer,
has no ERSPAN, VXLAN or Geneve)."""

from __future__ import annotations

import functools
import itertools
import random
import struct
from collections.abc import Callable
from pathlib import Path

import dpkt
import pytest

from rtde_spec.capture.decoder import capture_tables, decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import Conversation, rtde_packages, rtde_setup, write

CLIENT, SERVER = ("10.0.0.2", 51000), ("10.0.0.10", 30004)
BIG = ("timestamp", "actual_q", "robot_mode", "actual_TCP_pose")
OUTER = b"\x00\x1b\x21\x00\x00\x01" + b"\x00\x1b\x21\x00\x00\x02"  # the collector's link: dst, src MAC
A, B = bytes([192, 0, 2, 1]), bytes([192, 0, 2, 2])  # the tunnel's ends
A6, B6 = bytes.fromhex("20010db8" + "0" * 23 + "1"), bytes.fromhex("20010db8" + "0" * 23 + "2")


def ipv4(protocol: int, payload: bytes, ident: int = 0, fragment: int = 0) -> bytes:
    """RFC 791 section 3.1: version and IHL, TOS, total length, identification, flags and
    fragment offset, TTL, protocol, checksum (not checked), source, destination."""
    return (
        struct.pack(">BBHHHBBH4s4s", 0x45, 0, 20 + len(payload), ident, fragment, 64, protocol, 0, A, B)
        + payload
    )


def ipv6(next_header: int, payload: bytes) -> bytes:
    """RFC 8200 section 3: version, class and flow label, payload length, next header, hop limit,
    source, destination."""
    return struct.pack(">IHBB16s16s", 6 << 28, len(payload), next_header, 64, A6, B6) + payload


def ethernet(kind: int, payload: bytes) -> bytes:
    return OUTER + kind.to_bytes(2, "big") + payload


def udp(port: int, payload: bytes) -> bytes:
    """RFC 768: source port, destination port, length, checksum (0: none)."""
    return struct.pack(">HHHH", 49152, port, 8 + len(payload), 0) + payload


def gre(
    protocol: int, payload: bytes, *, key: int | None = None, seq: int | None = None, csum: bool = False
) -> bytes:
    """RFC 2784 section 2.1 (C bit 0x8000: checksum and reserved, 4 bytes; version 0 in the low 3
    bits; protocol type) with RFC 2890 section 2's key (K, 0x2000) and sequence number (S, 0x1000)."""
    flags = (0x8000 if csum else 0) | (0x2000 if key is not None else 0) | (0x1000 if seq is not None else 0)
    head = struct.pack(">HH", flags, protocol) + (b"\0" * 4 if csum else b"")
    return head + b"".join(struct.pack(">I", v) for v in (key, seq) if v is not None) + payload


def erspan2(frame: bytes, session: int = 5) -> bytes:
    """draft-foschiano-erspan-03 section 4.1: Ver (4 bits, 1), VLAN (12), COS (3), En (2), T (1),
    Session ID (10); Reserved (12), Index (20)."""
    return struct.pack(">II", 1 << 28 | session, 0) + frame


def erspan3(frame: bytes, session: int = 7, subheader: bool = False, ip_only: bool = False) -> bytes:
    """Section 4.2: Ver (2), VLAN, COS, BSO, T, Session ID; Timestamp (32); SGT (16), P (1), FT (5:
    0 Ethernet, 2 IP), Hw ID (6), D, Gra (2), O (1: an 8-byte platform-specific subheader follows)."""
    word = (2 if ip_only else 0) << 10 | 1 << 1 | subheader
    return struct.pack(">III", 2 << 28 | session, 123456, word) + b"\x05" * 8 * subheader + frame


def vxlan(frame: bytes, vni: int = 100) -> bytes:
    """RFC 7348 section 5: flags (I = 0x08), 24 reserved bits, VNI (24), 8 reserved bits."""
    return struct.pack(">II", 0x08 << 24, vni << 8) + frame


def geneve(frame: bytes, vni: int = 200) -> bytes:
    """RFC 8926 section 3.4: Ver (2) and Opt Len (6, 4-byte words), O, C, reserved, protocol type
    (0x6558: Ethernet), VNI, reserved; then the options (here one of 8 bytes: class, type, length)."""
    option = struct.pack(">HBB", 0x0101, 0x01, 1) + b"\xaa" * 4
    return struct.pack(">BBHI", len(option) // 4, 0, 0x6558, vni << 8) + option + frame


def mpls(payload: bytes, labels: tuple[int, ...] = (100, 200)) -> bytes:
    """RFC 3032 section 2.1: label (20 bits), traffic class (3), bottom of stack S (1), TTL (8)."""
    entries = [label << 12 | (k == len(labels) - 1) << 8 | 64 for k, label in enumerate(labels)]
    return b"".join(e.to_bytes(4, "big") for e in entries) + payload


def nflog(packet: bytes) -> bytes:
    """Linux's NFLOG record (tcpdump.org's LINKTYPE_NFLOG): family (2, IPv4), version 0, resource
    id (big-endian); then TLVs of length (with its 4-byte header) and type in the host's order,
    padded to 4 bytes: a prefix (10), then the packet (NFULA_PAYLOAD, 9)."""

    def tlv(kind: int, value: bytes) -> bytes:
        return struct.pack("<HH", 4 + len(value), kind) + value + b"\0" * (-len(value) % 4)

    return bytes([2, 0, 0, 1]) + tlv(10, b"rtde\0") + tlv(9, packet)


def tzsp(frame: bytes) -> bytes:
    """TZSP as a MikroTik streams its sniffer (Wireshark's packet-tzsp.c): version 1, type 0
    (received), encapsulation 1 (Ethernet); tags: PADDING (0), the sensor's MAC (60, length 6),
    END (1); then the frame."""
    return bytes([1, 0, 0, 1, 0, 60, 6]) + b"\x4c\x5e\x0c\x00\x00\x01" + bytes([1]) + frame


def fragments4(packet: bytes, size: int, ident: int) -> list[bytes]:
    """The IPv4 packet's payload in `size`-byte fragments, each with the packet's header (RFC 791
    section 3.1: total length, identification, MF 0x2000, offset in 8-byte units)."""
    body, out = packet[20:], []
    for at in range(0, len(body), size):
        head = bytearray(packet[:20])
        head[2:4] = (20 + len(body[at : at + size])).to_bytes(2, "big")
        head[4:6] = ident.to_bytes(2, "big")
        head[6:8] = ((0x2000 if at + size < len(body) else 0) | at // 8).to_bytes(2, "big")
        out.append(bytes(head) + body[at : at + size])
    return out


def fragments6(packet: bytes, size: int, ident: int) -> list[bytes]:
    """The IPv6 packet's payload in `size`-byte fragments, each after the packet's header and a
    fragment header (RFC 8200 section 4.5: next header, reserved, offset (13 bits, 8-byte units),
    2 reserved bits, M; identification)."""
    body, out = packet[40:], []
    for at in range(0, len(body), size):
        piece = struct.pack(">BBHI", packet[6], 0, at | (at + size < len(body)), ident) + body[at : at + size]
        head = bytearray(packet[:40])
        head[4:6], head[6] = len(piece).to_bytes(2, "big"), 44
        out.append(bytes(head) + piece)
    return out


Wrap = Callable[[int, bytes], list[bytes]]  # (frame number, the Ethernet frame) -> the frames carrying it
WRAPS: dict[str, tuple[int, Wrap]] = {  # name -> (link type, wrap)
    "gre": (1, lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x6558, f)))]),
    "gre_key_seq_csum": (
        1,
        lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x6558, f, key=7, seq=n, csum=True)))],
    ),
    "gre_ip": (1, lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x0800, f[14:])))]),
    "erspan1": (1, lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x88BE, f)))]),
    "erspan2": (1, lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x88BE, erspan2(f), seq=n)))]),
    "erspan2_ipv6": (1, lambda n, f: [ethernet(0x86DD, ipv6(47, gre(0x88BE, erspan2(f), seq=n)))]),
    "erspan3": (
        1,
        lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x22EB, erspan3(f, subheader=n % 2 == 0), seq=n)))],
    ),
    "erspan3_ip": (
        1,
        lambda n, f: [ethernet(0x0800, ipv4(47, gre(0x22EB, erspan3(f[14:], ip_only=True), seq=n)))],
    ),
    # a collector's 576-byte path: the outer packets in fragments, some in reverse order
    "erspan2_fragmented": (
        1,
        lambda n, f: [
            ethernet(0x0800, p)
            for p in fragments4(ipv4(47, gre(0x88BE, erspan2(f), seq=n)), 64, n)[:: 1 if n % 3 else -1]
        ],
    ),
    "vxlan": (1, lambda n, f: [ethernet(0x0800, ipv4(17, udp(4789, vxlan(f))))]),
    "vxlan_ipv6": (1, lambda n, f: [ethernet(0x86DD, ipv6(17, udp(4789, vxlan(f))))]),
    "geneve": (1, lambda n, f: [ethernet(0x0800, ipv4(17, udp(6081, geneve(f))))]),
    "mpls": (1, lambda n, f: [ethernet(0x8847, mpls(f[14:]))]),
    "mpls_ethernet_pseudowire": (1, lambda n, f: [ethernet(0x8847, mpls(b"\0" * 4 + f, (300,)))]),  # RFC 4448
    "ipip": (1, lambda n, f: [ethernet(0x0800, ipv4(4, f[14:]))]),
    "tzsp": (1, lambda n, f: [ethernet(0x0800, ipv4(17, udp(37008, tzsp(f))))]),
    "nflog": (239, lambda n, f: [nflog(f[14:])]),
    # ingress and egress of the robot's port mirrored as two ERSPAN sessions: one connection
    "erspan2_session_per_direction": (
        1,
        lambda n, f: [
            ethernet(0x0800, ipv4(47, gre(0x88BE, erspan2(f, 1 + (f[26:30] == bytes([10, 0, 0, 2]))), seq=n)))
        ],
    ),
    # the same port mirrored twice (two sessions, two collectors merged): copies of one connection
    "vxlan_twice": (1, lambda n, f: [ethernet(0x0800, ipv4(17, udp(4789, vxlan(f, vni)))) for vni in (1, 2)]),
}


def session() -> Conversation:
    """An RTDE session: setup, then 200 packages, the last 20 of them cut across segments."""
    conv = Conversation(CLIENT, SERVER)
    rtde_setup(conv, BIG)
    packages = rtde_packages(200, BIG)
    for package in packages[:180]:
        conv.send("server", package)
    stream = b"".join(packages[180:])
    for at in range(0, len(stream), 300):
        conv.send("server", stream[at : at + 300])
    return conv


def pcap(path: Path, frames: list[tuple[float, bytes]], linktype: int) -> Path:
    with open(path, "wb") as out:
        writer = dpkt.pcap.Writer(out, linktype=linktype)
        for ts, frame in frames:
            writer.writepkt(frame, ts=ts)
    return path


@pytest.mark.parametrize("name", list(WRAPS))
def test_traffic_carried_in_a_tunnel_decodes_to_the_rows_of_the_frames_captured_directly(
    tmp_path: Path, name: str
) -> None:
    """Every such file was 'nothing decoded ... no TCP segments' (or its frames not TCP), exit 3."""
    conv = session()
    expected = capture_tables(write(tmp_path / "plain.pcap", [conv]))
    assert expected["rtde_outputs_1"].num_rows == 200
    linktype, wrap = WRAPS[name]
    frames = sorted(conv.frames, key=lambda f: f[0])
    wrapped = [(ts, carrier) for n, (ts, frame) in enumerate(frames, 1) for carrier in wrap(n, frame)]
    sink = ArrowSink()
    summary = decode_capture(pcap(tmp_path / f"{name}.pcap", wrapped, linktype), sink)
    assert summary.problems() == []
    assert sink.tables() == expected
    assert [c.name for c in summary.connections] == ["10.0.0.2:51000-10.0.0.10:30004"]


def test_tcp_segments_in_ipv6_fragments_are_put_back_together(tmp_path: Path) -> None:
    """A host sends a segment larger than the path MTU in IPv6 fragments (RFC 8200 section 4.5).
    Every fragment was counted as 'a fragment of an IPv6 TCP segment (not put back together)': no
    rows, exit 3. Here the fragments of two datagrams come interleaved, some in reverse order,
    some twice (a second capture point)."""
    conv = Conversation(("fd00::2", 51000), ("fd00::10", 30004))
    rtde_setup(conv, BIG)
    for package in rtde_packages(200, BIG):
        conv.send("server", package)
    expected = capture_tables(write(tmp_path / "plain.pcap", [conv]))
    frames = sorted(conv.frames, key=lambda f: f[0])
    out: list[tuple[float, bytes]] = []
    rng = random.Random(8)
    for n in range(0, len(frames), 2):
        both = [
            [(ts, f[:14] + p) for p in fragments6(f[14:], 24, n + k)]
            for k, (ts, f) in enumerate(frames[n : n + 2])
        ]
        for pieces in both:
            if rng.random() < 0.3:
                pieces.reverse()
            if rng.random() < 0.2:
                pieces.append(pieces[0])
        out += [p for pair in itertools.zip_longest(*both) for p in pair if p is not None]
    sink = ArrowSink()
    summary = decode_capture(pcap(tmp_path / "fragments.pcap", out, 1), sink)
    assert summary.problems() == []
    assert sink.tables() == expected
    fragmented = [f for _, f in frames if len(f) - 14 - 40 > 24]  # the rest: one atomic fragment each
    assert summary.reading["ip_reassembled"] == len(fragmented) > 200


def test_an_ipv6_datagram_whose_fragment_never_came_costs_its_own_bytes(tmp_path: Path) -> None:
    conv = Conversation(("fd00::2", 51000), ("fd00::10", 30004))
    rtde_setup(conv, BIG)
    for package in rtde_packages(50, BIG):
        conv.send("server", package)
    frames = sorted(conv.frames, key=lambda f: f[0])
    out = [(ts, f[:14] + p) for n, (ts, f) in enumerate(frames) for p in fragments6(f[14:], 32, n)]
    lost = len(out) - 3 * 5 - 2  # the second fragment of the fifth package from the end
    summary = decode_capture(pcap(tmp_path / "lost.pcap", out[:lost] + out[lost + 1 :], 1), ArrowSink())
    assert summary.packages == 6 + 49  # the setup exchange, and every package but the one cut
    assert summary.damage() == [
        "4 IP fragments of datagrams whose other fragments never came (skipped)",  # of the 5 it was cut into
        "fd00::2:51000-fd00::10:30004: 1 TCP gaps, 112 bytes never captured",
    ]


DAMAGED: dict[str, tuple[bytes, str]] = {  # a frame, and what the summary says of it
    "GRE cut short": (ethernet(0x0800, ipv4(47, b"\x00\x00")), "shorter than its GRE header"),
    "GRE version 1 (PPTP)": (
        ethernet(0x0800, ipv4(47, struct.pack(">HH", 0x0001, 0x880B) + b"\xff\x03")),
        "a GRE header of version 1 (0 is read; 1 is PPTP's)",
    ),
    "ERSPAN II of version 2": (
        ethernet(0x0800, ipv4(47, gre(0x88BE, b"\x20" + erspan2(b"")[1:] + b"\0" * 60, seq=1))),
        "an ERSPAN type 2 header of version 2 (not 1)",
    ),
    "ERSPAN III's subheader past the packet": (
        ethernet(0x0800, ipv4(47, gre(0x22EB, erspan3(b"", subheader=True)[:12], seq=1))),
        "shorter than its ERSPAN type 3 platform-specific subheader",
    ),
    "VXLAN without its I flag": (
        ethernet(0x0800, ipv4(17, udp(4789, b"\0" * 8 + b"\0" * 60))),
        "a VXLAN header without its I flag (RFC 7348 section 5)",
    ),
    "Geneve of version 1": (
        ethernet(0x0800, ipv4(17, udp(6081, b"\x40" + geneve(b"\0" * 60)[1:]))),
        "a Geneve header of version 1 (0 is read)",
    ),
    "Geneve options past the packet": (
        ethernet(0x0800, ipv4(17, udp(6081, b"\x3f" + geneve(b"")[1:]))),
        "Geneve options past the end of the packet",
    ),
    "TZSP of version 2": (
        ethernet(0x0800, ipv4(17, udp(37008, b"\x02" + tzsp(b"\0" * 60)[1:]))),
        "a TZSP header of version 2 (1 is read)",
    ),
    "TZSP tags without their end": (
        ethernet(0x0800, ipv4(17, udp(37008, bytes([1, 0, 0, 1, 0, 0, 60, 6, 1, 2])))),
        "TZSP tags without their end",
    ),
    "MPLS stack with no bottom": (
        ethernet(0x8847, b"\x00\x01\x00\x40" * 20),
        "an MPLS label stack of more than 16 entries",
    ),
    "GRE in GRE, 12 deep": (
        ethernet(0x0800, functools.reduce(lambda p, _: ipv4(47, gre(0x0800, p)), range(12), ipv4(6, b""))),
        "tunnels nested more than 8 deep",
    ),
}


def test_damaged_tunnel_headers_cost_their_own_frames_each_reported_with_its_number(tmp_path: Path) -> None:
    """A header cut short, of another version or with a length past its packet is counted as a
    frame that does not decode, with why and the frame's number (as Wireshark numbers frames);
    every other frame of the file is decoded (GRE in GRE 12 deep was a RecursionError risk)."""
    conv = session()
    expected = capture_tables(write(tmp_path / "plain.pcap", [conv]))
    _, wrap = WRAPS["erspan2"]
    frames = sorted(conv.frames, key=lambda f: f[0])
    out = [(ts, wrap(n, frame)[0]) for n, (ts, frame) in enumerate(frames, 1)]
    for k, (frame, _) in enumerate(DAMAGED.values()):
        out.insert(10 + 15 * k, (out[10 + 15 * k][0], frame))  # frame number 11 + 15 k
    sink = ArrowSink()
    summary = decode_capture(pcap(tmp_path / "damaged.pcap", out, 1), sink)
    assert sink.tables() == expected
    why = "; ".join(f"1: {why} (frame {11 + 15 * k})" for k, (_, why) in enumerate(DAMAGED.values()))
    assert summary.damage() == [f"{len(DAMAGED)} frames whose IP/TCP headers do not decode (skipped): {why}"]


def test_fragments_lost_of_udp_are_no_damage_unless_a_tunnel_loses_the_bytes(tmp_path: Path) -> None:
    """Fragments of UDP are put back together for the tunnels UDP carries (VXLAN, Geneve). A lost
    fragment of other UDP (a big syslog or DNS datagram in the same capture) is nothing the tables
    lose: it made the capture 'damaged', exit 3. A VXLAN packet's lost fragment still shows as the
    gap it leaves in the inner connection."""
    conv = session()
    frames = sorted(conv.frames, key=lambda f: f[0])
    syslog = fragments4(ipv4(17, udp(514, b"<13>robot cell " * 40)), 200, 4242)
    lost_tunnel = fragments4(ipv4(17, udp(4789, vxlan(frames[20][1]))), 64, 4243)
    out = [(ts, ethernet(0x0800, ipv4(17, udp(4789, vxlan(f))))) for ts, f in frames]
    out[10:10] = [(out[10][0], ethernet(0x0800, p)) for p in syslog[:1] + syslog[2:]]
    out[20 + len(syslog) - 1] = (out[20][0], ethernet(0x0800, lost_tunnel[0]))  # its other fragments lost
    summary = decode_capture(pcap(tmp_path / "udp.pcap", out, 1), ArrowSink())
    assert summary.reading["ip_fragments_lost_udp"] == len(syslog) - 1 + 1
    assert summary.damage() == ["10.0.0.2:51000-10.0.0.10:30004: 1 TCP gaps, 112 bytes never captured"]


def test_ipv6_fragments_of_what_cannot_hold_tcp_are_not_tcp(tmp_path: Path) -> None:
    """A big ICMPv6 echo (`ping -s 3000`) in fragments, one lost: only what may hold TCP (TCP, option
    headers, tunnels) is put back together, as for IPv4; its lost fragments made the capture
    'damaged', exit 3, though the tables lose nothing."""
    conv = session()
    frames = sorted(conv.frames, key=lambda f: f[0])
    echo = fragments6(ipv6(58, struct.pack(">BBHHH", 128, 0, 0, 1, 1) + b"x" * 3000), 1232, 99)
    out = list(frames)
    out[12:12] = [(out[12][0], ethernet(0x86DD, p)) for p in echo[:-1]]  # its last fragment lost
    summary = decode_capture(pcap(tmp_path / "ping.pcap", out, 1), ArrowSink())
    assert summary.problems() == [] and summary.packages == 206
    assert summary.reading["not_tcp"] == len(echo) - 1


def test_wireshark_reads_the_tunnels_built_here_to_the_same_tcp_segments(tmp_path: Path) -> None:
    """The headers above are ours; tshark, an implementation independent of both, finds the same
    TCP segments in every wrapped file as in the plain one. Left out: the MPLS pseudowire (it needs
    Wireshark's 'Decode As') and ERSPAN III's frame type 2, IP (Wireshark shows its packet as data;
    the draft's section 4.2 names it "IP packet")."""
    import subprocess

    from tests.wireshark_tools import wireshark_tool

    tshark = wireshark_tool("tshark", ": the tunnel files are not checked against Wireshark")
    conv = session()
    frames = sorted(conv.frames, key=lambda f: f[0])

    def segments(path: Path) -> list[str]:
        fields = ["-T", "fields", "-e", "tcp.srcport", "-e", "tcp.seq_raw", "-e", "tcp.len"]
        done = subprocess.run(
            [tshark, "-r", str(path), "-Y", "tcp", *fields], capture_output=True, timeout=120
        )
        return sorted(set(done.stdout.decode().split("\n")))

    plain = segments(write(tmp_path / "plain.pcap", [conv]))
    assert len(plain) > 190
    for name, (linktype, wrap) in WRAPS.items():
        if name not in ("mpls_ethernet_pseudowire", "erspan3_ip"):
            wrapped = [(ts, carrier) for n, (ts, frame) in enumerate(frames, 1) for carrier in wrap(n, frame)]
            assert segments(pcap(tmp_path / f"{name}.pcap", wrapped, linktype)) == plain, name


def test_frames_a_mirror_session_cut_are_named_as_the_cause_of_their_gaps(tmp_path: Path) -> None:
    """A switch's ERSPAN session truncates mirrored frames past its MTU (the ERSPAN header's T bit,
    draft section 4.1). The inner packet is shorter than its IP length, and no capture record says
    so: the summary showed only TCP gaps, with no cause; it now names the mirror, as it names a
    snap length."""
    conv = session()
    frames = sorted(conv.frames, key=lambda f: f[0])
    cut = [len(f) > 120 for _, f in frames]

    def mirrored(n: int, frame: bytes) -> bytes:
        header = bytearray(erspan2(b""))
        header[2] |= 0x04 * (len(frame) > 120)  # T: the frame was truncated
        return ethernet(0x0800, ipv4(47, gre(0x88BE, bytes(header) + frame[:120], seq=n)))

    out = [(ts, mirrored(n, f)) for n, (ts, f) in enumerate(frames, 1)]
    summary = decode_capture(pcap(tmp_path / "truncated.pcap", out, 1), ArrowSink())
    assert summary.damage()[0] == (
        f"{sum(cut)} packets carried in tunnels hold less than their IP length says (the mirror cut them: "
        "an ERSPAN session's MTU or truncation): the rest of their TCP payload is not in the file (the "
        "gaps below); mirror whole frames to keep it"
    )
    assert "TCP gaps" in summary.damage()[1]


def test_unreadable_frames_past_the_reasons_kept_apart_are_still_told() -> None:
    """16 reasons are kept apart (each with its first frame); the rest were left out of the line,
    whose parts then did not add up to its count."""
    from rtde_spec.capture.reading.packets import _unreadable
    from rtde_spec.capture.tables.summary import CaptureSummary

    counts: dict[str, int] = {}
    for k in range(20):
        _unreadable(counts, f"a GRE header of version {k}", 100 + k)
    line = CaptureSummary("x.pcap", 200, reading=counts).damage()[0]
    assert line.startswith(
        "20 frames whose IP/TCP headers do not decode (skipped): 1: a GRE header of version 0"
    )
    assert line.endswith("1: a GRE header of version 15 (frame 115); 4: other reasons")
