"""A capture as either host takes it: the peer's ACK after (nearly) every data package.

Captures the tests and benchmarks made had no ACK frames; a real one (tcpdump or dumpcap on the
robot's network or on the recording PC) has one after nearly every package of a 500 Hz stream.
Record sizes then alternate, and every ACK ended a run of packages: such a capture was read
frame by frame, 8-10x slower (100,000 packages: 9.7 s against 1.0 s). Now it reads as fast
as one without them, and decodes to the same tables; so do Linux cooked captures
(`tcpdump -i any`) and frames with a VLAN tag, which were read frame by frame with or without ACKs.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import dpkt
import pytest

from rtde_spec.capture.decoder import decode_to_directory
from rtde_spec.capture.reading import packets, pcapfile
from rtde_spec.capture.reading.packets import Segment, items, segments
from tests.capture_files import ACK, Conversation, rtde_packages, rtde_setup, write

PACKAGES = 600


def _session(
    tmp_path: Path, name: str, acks: int, fmt: str = "pcap", stranger: bool = False, link: str = "ethernet"
) -> Path:
    """A recorder's session; the client ACKs every `acks`-th package (0: never) with the right
    number, and once a window update from the controller (`stranger`: and one ACK of another
    connection, which ends a run)."""
    framing = "ethernet" if link == "vlan" else link
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004), link=framing)
    other = Conversation(("10.0.0.3", 52000), ("10.0.0.11", 30004), link=framing)
    rtde_setup(conv)
    for i, package in enumerate(rtde_packages(PACKAGES)):
        conv.send("server", package)
        if acks and i % acks == acks - 1:
            _bare(conv, "client", conv.seq["server"])
        if i == 300:
            _bare(conv, "server", conv.seq["client"])  # a window update: the controller's own
        if stranger and i == 450:
            other.time = conv.time
            _bare(other, "client", 7)
    if link == "vlan":  # one 802.1Q tag (VLAN 5) after the addresses, as a switch's mirror port keeps it
        for conversation in (conv, other):
            conversation.frames = [(t, f[:12] + b"\x81\x00\x00\x05" + f[12:]) for t, f in conversation.frames]
    return write(tmp_path / f"{name}.{fmt}", [conv, other] if stranger else [conv], fmt)


def _bare(conv: Conversation, side: str, ack: int) -> None:
    """A segment without data from `side`, acknowledging `ack`."""
    (src, sport), (dst, dport) = (
        (conv.client, conv.server) if side == "client" else (conv.server, conv.client)
    )
    tcp = dpkt.tcp.TCP(sport=sport, dport=dport, seq=conv.seq[side], ack=ack, flags=ACK, win=512)
    ip = dpkt.ip.IP(src=bytes(map(int, src.split("."))), dst=bytes(map(int, dst.split("."))), p=6, data=tcp)
    if conv.link == "sll":  # Linux's cooked capture (tcpdump -i any)
        frame = dpkt.sll.SLL(
            type=0, hrd=772, hlen=6, hdr=b"\0" * 8, ethtype=dpkt.ethernet.ETH_TYPE_IP, data=ip
        )
    elif conv.link == "loopback":  # BSD loopback: the address family, then IP
        frame = (2).to_bytes(4, "little") + bytes(ip)
    else:
        frame = dpkt.ethernet.Ethernet(
            src=b"\x02" * 6, dst=b"\x04" * 6, type=dpkt.ethernet.ETH_TYPE_IP, data=ip
        )
    conv.time += 0.0001
    conv.frames.append((conv.time, bytes(frame)))


def _frames(path: Path, link: str = "ethernet") -> list[Segment]:
    """Every TCP segment of the file, read with dpkt (not our reader)."""
    out = []
    reader = dpkt.pcapng.Reader if path.suffix == ".pcapng" else dpkt.pcap.Reader
    with open(path, "rb") as f:
        for ts, frame in reader(f):
            layer = {"sll": dpkt.sll.SLL, "loopback": dpkt.loopback.Loopback}.get(
                link, dpkt.ethernet.Ethernet
            )
            ip = layer(frame).data
            tcp = ip.data
            src, dst = ".".join(map(str, ip.src)), ".".join(map(str, ip.dst))
            ack = tcp.ack if tcp.flags & ACK else -1
            out.append(Segment(ts, src, tcp.sport, dst, tcp.dport, tcp.seq, tcp.flags, bytes(tcp.data), ack))
    return out


def _table(out: Path) -> Any:
    import pyarrow.parquet as pq

    (path,) = out.glob("rtde_outputs_1/**/*.parquet")
    return pq.read_table(path)


CASES = [(fmt, acks, "ethernet") for fmt in ("pcap", "pcapng") for acks in (1, 2, 3)]
CASES += [("pcap", 1, "sll"), ("pcapng", 2, "vlan"), ("pcap", 3, "loopback")]  # -i any; a mirror port


@pytest.mark.parametrize(("fmt", "acks", "link"), CASES)
def test_a_capture_with_the_peers_acks_decodes_to_the_same_table_read_a_run_at_a_time(
    tmp_path: Path, fmt: str, acks: int, link: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    plain = _session(tmp_path, "plain", 0, fmt, link=link)
    acked = _session(tmp_path, "acked", acks, fmt, link=link)
    one_by_one: list[int] = []
    real = packets._segment
    monkeypatch.setattr(packets, "_segment", lambda *a: one_by_one.append(1) or real(*a))
    walked: list[int] = []
    same_run = pcapfile.same_run
    monkeypatch.setattr(pcapfile, "same_run", lambda *a: walked.append(1) or same_run(*a))
    summary = decode_to_directory(acked, tmp_path / "acked-out")
    assert summary.tables["rtde_outputs_1"] == PACKAGES
    frames = len(_frames(acked, link))
    assert summary.frames == frames > PACKAGES
    # the handshake, the setup and the ACKs before the first run; not every frame (before: all)
    assert len(one_by_one) < 40 and len(walked) < 40, (len(one_by_one), len(walked))
    decode_to_directory(plain, tmp_path / "plain-out")
    got, want = (_table(tmp_path / f"{name}-out") for name in ("acked", "plain"))
    assert got.drop(["capture_time"]).equals(want.drop(["capture_time"]))  # the ACKs took time


@pytest.mark.parametrize(("fmt", "link"), [("pcap", "ethernet"), ("pcapng", "ethernet"), ("pcap", "sll")])
def test_a_run_read_one_by_one_gives_back_every_segment_in_its_place(
    tmp_path: Path, fmt: str, link: str
) -> None:
    """What a run stands for, expanded (a connection that cannot take it whole reads it so), is
    every segment of the file in order: packages, the ACKs of both sides between them, and an
    ACK of another connection, which ends the run."""
    path = _session(tmp_path, "acked", 1, fmt, stranger=True, link=link)
    runs = [item for item in items(path, interleaved=False) if not isinstance(item, Segment)]
    assert len(runs) >= 2 and all(run.bare is not None for run in runs)
    ours, theirs = list(segments(path)), _frames(path, link)
    assert len(ours) == len(theirs)
    for got, want in zip(ours, theirs, strict=True):
        assert got.payload == want.payload and got[1:6] == want[1:6] and got.time == pytest.approx(want.time)
        if not got.payload:  # a run's packages do not carry their flags and ACK numbers
            assert (got.flags, got.ack) == (want.flags, want.ack)


def test_frames_read_one_by_one_still_batch_their_packages_over_the_acks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Linux's cooked captures (`tcpdump -i any`) are read frame by frame; there too an ACK of the
    connection no longer ends the batch of its packages (each package was decoded on its own)."""
    from rtde_spec.capture.protocols.rtde import RtdeConnection

    plain = _session(tmp_path, "plain", 0, link="sll")
    acked = _session(tmp_path, "acked", 1, link="sll")
    batches: list[int] = []
    feed_run = RtdeConnection.feed_run
    monkeypatch.setattr(
        RtdeConnection, "feed_run", lambda self, *a: batches.append(len(a[2])) or feed_run(self, *a)
    )
    decode_to_directory(acked, tmp_path / "acked-out")
    assert sum(batches) > PACKAGES - 40 and len(batches) < 10, batches
    decode_to_directory(plain, tmp_path / "plain-out")
    got, want = (_table(tmp_path / f"{name}-out") for name in ("acked", "plain"))
    assert got.drop(["capture_time"]).equals(want.drop(["capture_time"]))


@pytest.mark.parametrize("fmt", ["pcap", "pcapng"])
def test_frames_a_snap_length_cut_are_counted_when_sizes_take_turns(tmp_path: Path, fmt: str) -> None:
    """Records read in pairs or one by one still count the frames cut short (their original length
    over what the file holds): each package's record says it had 10 bytes more."""
    path = _session(tmp_path, "acked", 1, fmt)
    data = bytearray(path.read_bytes())
    pos, cut = (24, 0) if fmt == "pcap" else (0, 0)
    while pos < len(data):
        if fmt == "pcap":
            caplen = int.from_bytes(data[pos + 8 : pos + 12], "little")
            if caplen > 100:
                data[pos + 12 : pos + 16] = (caplen + 10).to_bytes(4, "little")
                cut += 1
            pos += 16 + caplen
        else:
            kind, length = (int.from_bytes(data[pos + k : pos + k + 4], "little") for k in (0, 4))
            if kind == 6 and int.from_bytes(data[pos + 20 : pos + 24], "little") > 100:
                caplen = int.from_bytes(data[pos + 20 : pos + 24], "little")
                data[pos + 24 : pos + 28] = (caplen + 10).to_bytes(4, "little")
                cut += 1
            pos += length
    path.write_bytes(bytes(data))
    stats: dict[str, int] = {}
    assert sum(1 for _ in items(path, stats)) > 0
    assert stats["cut_frames"] == cut >= PACKAGES
