"""Traffic inside tunnels, unwrapped to the frame or packet it carries, then read as if captured
directly: a robot cell's switch port mirrored to a collector (ERSPAN over GRE), an overlay
network (VXLAN, Geneve), a GRE or IP-in-IP tunnel, an MPLS label stack, a MikroTik's sniffer
stream (TZSP), and Linux's NFLOG.

Each header is read as its specification lays it out (cited where it is read); a header cut
short, of another version or with a length past its packet raises ValueError naming it: the
frame is counted as unreadable (with its frame number), never passed over as "not TCP".
Frames of different tunnels (GRE keys, ERSPAN sessions, VNIs) are not kept apart: a connection
is its inner addresses and ports, so both directions of a port mirrored as two ERSPAN sessions
(ingress and egress) are one connection, and the same traffic mirrored twice is taken as copies.
"""

from __future__ import annotations

ETHERNET, IPV4, IPV6 = 0x6558, 0x0800, 0x86DD  # GRE's "transparent Ethernet bridging" (RFC 1701)
MPLS = (0x8847, 0x8848)  # unicast, multicast (RFC 5332)
VLAN = (0x8100, 0x88A8, 0x9100)  # 802.1Q, 802.1ad, and the QinQ tag before 802.1ad (Wireshark reads it)
ERSPAN_2, ERSPAN_3 = 0x88BE, 0x22EB  # GRE protocol types of ERSPAN type I/II and type III
GRE, UDP, IPIP, IPV6_IN_IP = 47, 17, 4, 41  # IP protocol numbers of what may carry TCP inside
CARRIERS = frozenset((GRE, UDP, IPIP, IPV6_IN_IP))
VXLAN_PORT, GENEVE_PORT = 4789, 6081  # IANA's UDP ports (RFC 7348 section 5; RFC 8926 section 3.3)
TZSP_PORT = 37008  # MikroTik's "packet sniffer" streaming (TaZmen Sniffer Protocol; Wireshark's port)
MAX_LABELS = 16  # MPLS label stack entries read before the stack is taken as damage
Start = tuple[int, int]  # (ethertype of what starts there, its offset in the frame)


def ethernet(frame: bytes, at: int) -> Start:
    """The ethertype and start of what an Ethernet header at `at` carries (past VLAN tags)."""
    if len(frame) < at + 14:
        raise ValueError("shorter than its Ethernet header")
    at, kind = at + 12, int.from_bytes(frame[at + 12 : at + 14], "big")
    while kind in VLAN:
        at += 4
        if len(frame) < at + 2:
            raise ValueError("shorter than its VLAN tags")
        kind = int.from_bytes(frame[at : at + 2], "big")
    return kind, at + 2


def inner(protocol: int, frame: bytes, at: int, end: int) -> Start | None:
    """What the payload of IP protocol `protocol` at frame[at:end] carries; None when it is no
    tunnel (UDP to another port)."""
    if protocol == IPIP:  # RFC 2003
        return IPV4, at
    if protocol == IPV6_IN_IP:  # RFC 4213, RFC 2473
        return IPV6, at
    if protocol == GRE:
        return _gre(frame, at, end)
    if end < at + 8:  # UDP, RFC 768: ports, length, checksum
        raise ValueError("shorter than its UDP header")
    port = int.from_bytes(frame[at + 2 : at + 4], "big")
    if port == VXLAN_PORT:
        return _vxlan(frame, at + 8, end)
    if port == GENEVE_PORT:
        return _geneve(frame, at + 8, end)
    if port == TZSP_PORT:
        return _tzsp(frame, at + 8, end)
    return None


def _gre(frame: bytes, at: int, end: int) -> Start | None:
    """RFC 2784 section 2 (C: checksum and reserved, 4 bytes; version 0) with RFC 2890's key (K)
    and sequence number (S), 4 bytes each; RFC 1701's routing (R) is not read."""
    if end < at + 4:
        raise ValueError("shorter than its GRE header")
    flags, protocol = int.from_bytes(frame[at : at + 2], "big"), int.from_bytes(frame[at + 2 : at + 4], "big")
    if flags & 0x0007:
        raise ValueError(f"a GRE header of version {flags & 7} (0 is read; 1 is PPTP's)")
    if flags & 0x4000:
        raise ValueError("a GRE header with source routing (RFC 1701), not read")
    size = 4 + 4 * (bool(flags & 0x8000) + bool(flags & 0x2000) + bool(flags & 0x1000))
    if end < at + size:
        raise ValueError("shorter than its GRE header")
    at += size
    if protocol == ERSPAN_2:
        if not flags & 0x1000:  # type I: no sequence number and no ERSPAN header (Wireshark's rule)
            return ethernet(frame, at)
        return _erspan(frame, at, end, 1, 8)
    if protocol == ERSPAN_3:
        return _erspan(frame, at, end, 2, 12)
    return _carried(protocol, frame, at)


def _erspan(frame: bytes, at: int, end: int, version: int, size: int) -> Start:
    """ERSPAN type II (version 1, 8 bytes) and III (version 2, 12 bytes, and 8 more when its O
    flag says a platform-specific subheader follows) headers, draft-foschiano-erspan-03 sections
    4.1-4.2; type III's frame type (FT) 0 is Ethernet, 2 an IP packet."""
    if end < at + size:
        raise ValueError(f"shorter than its ERSPAN type {version + 1} header")
    if frame[at] >> 4 != version:
        raise ValueError(f"an ERSPAN type {version + 1} header of version {frame[at] >> 4} (not {version})")
    if version == 1:
        return ethernet(frame, at + 8)
    word = int.from_bytes(frame[at + 8 : at + 12], "big")
    at += 12 + 8 * (word & 1)
    if end < at:
        raise ValueError("shorter than its ERSPAN type 3 platform-specific subheader")
    kind = (word >> 10) & 0x1F
    if kind == 0:
        return ethernet(frame, at)
    if kind == 2:
        return (IPV4 if at < end and frame[at] >> 4 == 4 else IPV6), at
    raise ValueError(f"an ERSPAN type 3 frame type {kind} (0, Ethernet, and 2, IP, are read)")


def _vxlan(frame: bytes, at: int, end: int) -> Start:
    """RFC 7348 section 5: flags (I, 0x08, set for a valid VNI), 24 reserved bits, VNI, 8 reserved
    bits; then an Ethernet frame."""
    if end < at + 8:
        raise ValueError("shorter than its VXLAN header")
    if not frame[at] & 0x08:
        raise ValueError("a VXLAN header without its I flag (RFC 7348 section 5)")
    return ethernet(frame, at + 8)


def _geneve(frame: bytes, at: int, end: int) -> Start | None:
    """RFC 8926 section 3.4: version (2 bits, 0), options length (6 bits, 4-byte words), O and C
    flags, protocol type (an ethertype: 0x6558 Ethernet), VNI; then the options and the payload."""
    if end < at + 8:
        raise ValueError("shorter than its Geneve header")
    if frame[at] >> 6:
        raise ValueError(f"a Geneve header of version {frame[at] >> 6} (0 is read)")
    start = at + 8 + (frame[at] & 0x3F) * 4
    if end < start:
        raise ValueError("Geneve options past the end of the packet")
    return _carried(int.from_bytes(frame[at + 2 : at + 4], "big"), frame, start)


def _tzsp(frame: bytes, at: int, end: int) -> Start | None:
    """TZSP, as a MikroTik switch or router streams what its packet sniffer sees (Wireshark's
    packet-tzsp.c, after Network Chemistry's note AN001): version 1, type (0: received, 1: for
    transmit), encapsulation (1: Ethernet); then tags up to END (1): PADDING (0) alone, any other
    with a length byte; then the frame."""
    if end < at + 4:
        raise ValueError("shorter than its TZSP header")
    if frame[at] != 1:
        raise ValueError(f"a TZSP header of version {frame[at]} (1 is read)")
    if frame[at + 1] > 1 or int.from_bytes(frame[at + 2 : at + 4], "big") != 1:
        return None  # a keepalive or configuration, or a frame not Ethernet (802.11)
    at += 4
    while at < end and frame[at] != 1:
        at += 1 if frame[at] == 0 else 2 + (frame[at + 1] if at + 1 < end else 0)
    if at >= end:
        raise ValueError("TZSP tags without their end")
    return ethernet(frame, at + 1)


def _carried(protocol: int, frame: bytes, at: int) -> Start | None:
    """What an ethertype-like protocol field names: an Ethernet frame, or IP/MPLS directly."""
    if protocol == ETHERNET:
        return ethernet(frame, at)
    if protocol in (IPV4, IPV6, *MPLS):
        return protocol, at
    return None


def mpls(frame: bytes, at: int, end: int) -> Start | None:
    """RFC 3032 section 2.1: 4-byte label stack entries up to the one with S (bottom of stack);
    what follows has no type field: IPv4 or IPv6 by its version nibble, or a pseudowire control
    word (first nibble 0, RFC 4385) and an Ethernet frame (RFC 4448)."""
    for _ in range(MAX_LABELS):
        if end < at + 4:
            raise ValueError("shorter than its MPLS label stack")
        at += 4
        if frame[at - 2] & 0x01:
            break
    else:
        raise ValueError(f"an MPLS label stack of more than {MAX_LABELS} entries")
    if end <= at:
        return None
    first = frame[at] >> 4
    if first in (4, 6):
        return (IPV4 if first == 4 else IPV6), at
    if first == 0:
        return ethernet(frame, at + 4)
    return None


def nflog(frame: bytes) -> Start:
    """Linux NFLOG (link type 239, `tcpdump -i nflog:N`): family, version 0 and resource id, then
    type-length-value attributes whose length (including its 4-byte header) and type are in the
    capturing host's byte order, padded to 4 bytes; NFULA_PAYLOAD (9) is the IP packet."""
    if len(frame) < 4:
        raise ValueError("shorter than its NFLOG header")
    if frame[1] != 0:
        raise ValueError(f"an NFLOG header of version {frame[1]} (0 is read)")
    for order in ("little", "big"):
        at = 4
        while at + 4 <= len(frame):
            size = int.from_bytes(frame[at : at + 2], order)  # type: ignore[arg-type]
            kind = int.from_bytes(frame[at + 2 : at + 4], order)  # type: ignore[arg-type]
            if size < 4 or at + size > len(frame):
                break
            if kind & 0x7FFF == 9:
                start = at + 4
                return (IPV4 if start < len(frame) and frame[start] >> 4 == 4 else IPV6), start
            at += (size + 3) // 4 * 4
    raise ValueError("an NFLOG record without its packet (NFULA_PAYLOAD)")
