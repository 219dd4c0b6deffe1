"""TCP segments out of pcap and pcapng files, through dpkt.

Link types: Ethernet, Linux cooked (SLL and SLL2), BSD loopback/null and raw IP;
IPv4 and IPv6. Anything else is counted, not decoded.
"""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtde_spec.errors import UsageError, require

FIN, SYN, RST = 0x01, 0x02, 0x04


@dataclass(frozen=True)
class Segment:
    time: float
    src: str
    sport: int
    dst: str
    dport: int
    seq: int
    flags: int
    payload: bytes


def _ip_of(dpkt: Any, linktype: int, frame: bytes) -> Any:
    if linktype == 1:  # Ethernet
        return dpkt.ethernet.Ethernet(frame).data
    if linktype == 113:  # Linux cooked v1
        return dpkt.sll.SLL(frame).data
    if linktype == 276:  # Linux cooked v2
        return dpkt.sll2.SLL2(frame).data
    if linktype in (0, 108):  # BSD loopback / OpenBSD loop: a 4-byte family, then IP
        version = frame[4] >> 4 if len(frame) > 4 else 0
        return (dpkt.ip.IP if version == 4 else dpkt.ip6.IP6)(frame[4:])
    if linktype in (101, 12, 14):  # raw IP
        return (dpkt.ip.IP if frame[0] >> 4 == 4 else dpkt.ip6.IP6)(frame)
    return None


def segments(
    path: str | Path, stats: dict[str, int] | None = None, progress: Callable[[int], None] | None = None
) -> Iterator[Segment]:
    """Every TCP segment of a capture file, in file order; `progress(bytes read)` now and then."""
    dpkt = require("dpkt", "capture", "reading captures")
    counts = stats if stats is not None else {}
    with open(path, "rb") as f:
        magic = f.read(4)
        f.seek(0)
        try:
            reader = dpkt.pcapng.Reader(f) if magic == b"\x0a\x0d\x0d\x0a" else dpkt.pcap.Reader(f)
        except (ValueError, dpkt.dpkt.NeedData) as exc:
            raise UsageError(f"not a pcap or pcapng file ({exc})", subject=f"file {path}") from None
        linktype = reader.datalink()
        for ts, frame in reader:
            counts["frames"] = counts.get("frames", 0) + 1
            if progress is not None and counts["frames"] % 4096 == 0:
                progress(f.tell())
            try:
                ip = _ip_of(dpkt, linktype, frame)
            except (dpkt.dpkt.UnpackError, IndexError):
                counts["undecodable"] = counts.get("undecodable", 0) + 1
                continue
            tcp = getattr(ip, "data", None)
            if not isinstance(tcp, dpkt.tcp.TCP):
                counts["not_tcp"] = counts.get("not_tcp", 0) + 1
                continue
            family = socket.AF_INET6 if isinstance(ip, dpkt.ip6.IP6) else socket.AF_INET
            yield Segment(
                float(ts),
                socket.inet_ntop(family, ip.src),
                tcp.sport,
                socket.inet_ntop(family, ip.dst),
                tcp.dport,
                tcp.seq,
                tcp.flags,
                bytes(tcp.data),
            )
