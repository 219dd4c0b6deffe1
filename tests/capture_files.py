"""Capture files made by the tests themselves: TCP conversations written frame by frame with dpkt."""

from __future__ import annotations

import socket
from dataclasses import dataclass, field
from pathlib import Path

import dpkt

ACK, PSH, SYN = dpkt.tcp.TH_ACK, dpkt.tcp.TH_PUSH, dpkt.tcp.TH_SYN


def _ip(src: str, dst: str, tcp: dpkt.tcp.TCP) -> dpkt.Packet:
    if ":" in src:
        return dpkt.ip6.IP6(
            src=socket.inet_pton(socket.AF_INET6, src), dst=socket.inet_pton(socket.AF_INET6, dst),
            nxt=dpkt.ip.IP_PROTO_TCP, hlim=64, data=tcp, plen=len(bytes(tcp)),
        )  # fmt: skip
    return dpkt.ip.IP(src=socket.inet_aton(src), dst=socket.inet_aton(dst), p=dpkt.ip.IP_PROTO_TCP, data=tcp)


@dataclass
class Conversation:
    """One TCP connection; frames are (time, bytes) as the chosen link type carries them."""

    client: tuple[str, int]
    server: tuple[str, int]
    link: str = "ethernet"  # ethernet | sll | loopback
    time: float = 1_700_000_000.0
    seq: dict[str, int] = field(default_factory=lambda: {"client": 1000, "server": 5000})
    frames: list[tuple[float, bytes]] = field(default_factory=list)

    def _frame(self, side: str, seq: int, payload: bytes, flags: int) -> bytes:
        (src, sport), (dst, dport) = (
            (self.client, self.server) if side == "client" else (self.server, self.client)
        )
        tcp = dpkt.tcp.TCP(sport=sport, dport=dport, seq=seq, ack=0, flags=flags, data=payload)
        ip = _ip(src, dst, tcp)
        if self.link == "sll":
            proto = dpkt.ethernet.ETH_TYPE_IP6 if ":" in src else dpkt.ethernet.ETH_TYPE_IP
            return bytes(dpkt.sll.SLL(type=0, hrd=772, hlen=6, hdr=b"\0" * 8, ethtype=proto, data=ip))
        if self.link == "loopback":
            family = 30 if ":" in src else 2
            return family.to_bytes(4, "little") + bytes(ip)
        ethtype = dpkt.ethernet.ETH_TYPE_IP6 if ":" in src else dpkt.ethernet.ETH_TYPE_IP
        return bytes(dpkt.ethernet.Ethernet(src=b"\x02" * 6, dst=b"\x04" * 6, type=ethtype, data=ip))

    def handshake(self) -> None:
        self.frames.append((self.time, self._frame("client", self.seq["client"], b"", SYN)))
        self.seq["client"] += 1
        self.frames.append((self.time, self._frame("server", self.seq["server"], b"", SYN | ACK)))
        self.seq["server"] += 1

    def send(self, side: str, data: bytes, dt: float = 0.002, keep: bool = True) -> tuple[int, bytes]:
        """One segment; `keep=False` leaves it out of the capture (a lost segment). Returns it."""
        self.time += dt
        seq = self.seq[side]
        frame = self._frame(side, seq, data, ACK | PSH)
        if keep:
            self.frames.append((self.time, frame))
        self.seq[side] += len(data)
        return seq, frame

    def resend(self, frame: bytes, dt: float = 0.001) -> None:
        self.time += dt
        self.frames.append((self.time, frame))


def write(path: Path, conversations: list[Conversation], fmt: str = "pcap") -> Path:
    """All conversations' frames, in time order, to a pcap or pcapng file."""
    link = conversations[0].link
    linktype = {
        "ethernet": dpkt.pcap.DLT_EN10MB,
        "sll": dpkt.pcap.DLT_LINUX_SLL,
        "loopback": dpkt.pcap.DLT_NULL,
    }[link]
    frames = sorted((f for c in conversations for f in c.frames), key=lambda f: f[0])
    with open(path, "wb") as out:
        writer = (
            dpkt.pcapng.Writer(out, linktype=linktype)
            if fmt == "pcapng"
            else dpkt.pcap.Writer(out, linktype=linktype)
        )
        for ts, frame in frames:
            writer.writepkt(frame, ts=ts)
    return path


# --- RTDE sessions with losses, for the fault tests and benchmarks/faults_capture.py ---

SMALL = ("timestamp", "actual_q", "robot_mode")  # a 64-byte data package
INPUTS = ("input_int_register_24", "speed_slider_fraction")


def rtde_setup(conv: Conversation, names: tuple[str, ...] = SMALL, recipe_id: int = 1) -> None:
    """Handshake, version, output and input setup, start: what a recorder sends first."""
    from rtde_spec import Catalogue, build

    cat = Catalogue.builtin()
    types = [cat.get(n, "output").type for n in names]  # type: ignore[union-attr]
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=list(names)))
    conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=recipe_id, variable_types=types))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))


def rtde_packages(count: int, names: tuple[str, ...] = SMALL, recipe_id: int = 1) -> list[bytes]:
    """`count` data packages; `timestamp` is the package's index times 2 ms, floats i + 0.5,
    integers i % 100 (vectors repeat the value)."""
    from rtde_spec import Catalogue, RecipeCodec

    codec = RecipeCodec.for_names(list(names), "output", Catalogue.builtin())
    out = []
    for i in range(count):
        values: dict[str, object] = {}
        for item in codec.items:
            one: object = (i + 0.5) if item.wire.kind == "float" else (i % 100)
            values[item.name] = tuple([one] * item.wire.count) if item.wire.count > 1 else one
        values["timestamp"] = i * 0.002
        out.append(codec.encode_package(values, recipe_id=recipe_id))
    return out


def rtde_capture(
    path: Path,
    packages: list[bytes],
    *,
    lost: set[int] = frozenset(),  # type: ignore[assignment]
    segment: int | None = None,
    names: tuple[str, ...] = SMALL,
    fmt: str = "pcap",
) -> Path:
    """An RTDE session: setup, then `packages` from the controller, one per segment or cut
    into `segment`-byte segments; the segments numbered in `lost` are left out."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv, names)
    if segment is None:
        pieces = packages
    else:
        stream = b"".join(packages)
        pieces = [stream[i : i + segment] for i in range(0, len(stream), segment)]
    for n, piece in enumerate(pieces):
        conv.send("server", piece, keep=n not in lost)
    return write(path, [conv], fmt)


def packages_touched(packages: list[bytes], segment: int, lost: set[int]) -> set[int]:
    """Indexes of the packages that share a byte with a lost `segment`-byte segment."""
    touched, start = set(), 0
    for i, package in enumerate(packages):
        end = start + len(package)
        if any(start < (s + 1) * segment and s * segment < end for s in lost):
            touched.add(i)
        start = end
    return touched
