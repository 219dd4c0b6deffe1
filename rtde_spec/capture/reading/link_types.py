"""The link types (pcap's LINKTYPE_ numbers) whose frames are read here, and where their IP
header starts: one table for the frame-by-frame reader (packets.py) and the numpy pass that
finds runs of data packages (bulk.py)."""

from __future__ import annotations

ETHERNET = 1  # the IP header after 14 bytes (more behind VLAN tags: tunnels.ethernet)
COOKED = {113: (14, 16), 276: (0, 20)}  # Linux cooked v1, v2 (`-i any`): (protocol at, IP at)
LOOPBACK = (0, 108)  # BSD loopback, OpenBSD loop: a 4-byte address family, then IP
RAW_IP = (101, 12, 14, 228, 229)  # nothing before the IP header (228: IPv4 only, 229: IPv6 only)
LINK_HEADERS = {ETHERNET: 14, **{link: ip for link, (_, ip) in COOKED.items()}, 0: 4, 108: 4}
