"""The struct-based capture reader on files it must read: byte orders, time units, pcapng blocks.

Frames are built by dpkt (an independent implementation); the file containers are
packed here by hand from the pcap and pcapng formats, so each variant is exercised.
"""

from __future__ import annotations

import os
import socket
import struct
import threading
from pathlib import Path

import dpkt
import pytest

from rtde_spec.capture.reading import pcapfile
from rtde_spec.capture.reading.bulk import DataRun
from rtde_spec.capture.reading.packets import Segment, items, segments
from rtde_spec.errors import UsageError

PAYLOAD = b"\x00\x05V\x00\x02"  # an RTDE version request


def ip_tcp(v6: bool = False, seq: int = 7, payload: bytes = PAYLOAD) -> bytes:
    tcp = dpkt.tcp.TCP(sport=51000, dport=30004, seq=seq, ack=1, flags=dpkt.tcp.TH_ACK, data=payload)
    if v6:
        src, dst = socket.inet_pton(socket.AF_INET6, "fd00::2"), socket.inet_pton(socket.AF_INET6, "fd00::10")
        return bytes(dpkt.ip6.IP6(src=src, dst=dst, nxt=6, hlim=64, data=tcp, plen=len(bytes(tcp))))
    return bytes(
        dpkt.ip.IP(src=socket.inet_aton("10.0.0.2"), dst=socket.inet_aton("10.0.0.10"), p=6, data=tcp)
    )


def ethernet(ip: bytes, vlan: bool = False, pad: int = 0) -> bytes:
    tag = b"\x81\x00\x00\x64" if vlan else b""
    kind = b"\x86\xdd" if ip[0] >> 4 == 6 else b"\x08\x00"
    return b"\x04" * 6 + b"\x02" * 6 + tag + kind + ip + b"\x00" * pad  # padding after the IP packet


def pcap(
    frames: list[tuple[int, int, bytes]], order: str = "<", nano: bool = False, linktype: int = 1
) -> bytes:
    magic = 0xA1B23C4D if nano else 0xA1B2C3D4
    out = struct.pack(order + "IHHiIII", magic, 2, 4, 0, 0, 65535, linktype)
    for sec, frac, frame in frames:
        out += struct.pack(order + "IIII", sec, frac, len(frame), len(frame)) + frame
    return out


def block(btype: int, body: bytes, order: str = "<") -> bytes:
    body += b"\x00" * (-len(body) % 4)
    length = len(body) + 12
    return struct.pack(order + "II", btype, length) + body + struct.pack(order + "I", length)


def pcapng(order: str = "<") -> bytes:
    shb = block(0x0A0D0D0A, struct.pack(order + "IHHq", 0x1A2B3C4D, 1, 0, -1), order)
    idb_eth = block(1, struct.pack(order + "HHI", 1, 0, 65535), order)
    tsresol = struct.pack(order + "HH", 9, 1) + b"\x09" + b"\x00" * 3 + struct.pack(order + "HH", 0, 0)
    idb_raw = block(1, struct.pack(order + "HHI", 101, 0, 65535) + tsresol, order)  # nanoseconds
    frame1 = ethernet(ip_tcp(seq=1))
    epb1 = block(6, struct.pack(order + "IIIII", 0, 0, 1_500_000, len(frame1), len(frame1)) + frame1, order)
    frame2 = ip_tcp(v6=True, seq=2)
    stamp = 2_250_000_000  # 2.25 s in nanoseconds
    epb2 = struct.pack(order + "IIIII", 1, stamp >> 32, stamp & 0xFFFFFFFF, len(frame2), len(frame2))
    custom = block(0xBAD, b"skipped", order)
    spb = block(3, struct.pack(order + "I", len(frame1)) + ethernet(ip_tcp(seq=3)), order)
    return shb + idb_eth + idb_raw + epb1 + block(6, epb2 + frame2, order) + custom + spb


def read(tmp_path: Path, data: bytes) -> tuple[list, dict[str, int]]:
    path = tmp_path / "capture"
    path.write_bytes(data)
    stats: dict[str, int] = {}
    return list(segments(path, stats)), stats


@pytest.mark.parametrize("order", ["<", ">"])
@pytest.mark.parametrize("nano", [False, True])
def test_classic_pcap_in_both_byte_orders_and_time_units(tmp_path: Path, order: str, nano: bool) -> None:
    frac = 250_000_000 if nano else 250_000
    frames = [(100, frac, ethernet(ip_tcp(seq=9), pad=6)), (101, 0, ethernet(ip_tcp(v6=True), vlan=True))]
    segs, stats = read(tmp_path, pcap(frames, order, nano))
    assert stats["frames"] == 2 and "not_tcp" not in stats
    first, second = segs
    assert first.time == pytest.approx(100.25) and second.time == 101.0
    assert (first.src, first.sport, first.dst, first.dport, first.seq) == (
        "10.0.0.2",
        51000,
        "10.0.0.10",
        30004,
        9,
    )
    assert first.payload == PAYLOAD  # the Ethernet padding after the IP packet is not payload
    assert (second.src, second.dst, second.payload) == ("fd00::2", "fd00::10", PAYLOAD)


@pytest.mark.parametrize("order", ["<", ">"])
def test_pcapng_interfaces_resolutions_and_blocks(tmp_path: Path, order: str) -> None:
    segs, stats = read(tmp_path, pcapng(order))
    assert [s.seq for s in segs] == [1, 2, 3] and all(s.payload == PAYLOAD for s in segs)
    assert segs[0].time == pytest.approx(1.5)  # microseconds by default
    assert segs[1].time == pytest.approx(2.25) and segs[1].src == "fd00::2"  # raw IPv6, nanoseconds
    assert stats["frames"] == 3


def test_what_is_not_tcp_is_counted_and_a_cut_record_reported(tmp_path: Path) -> None:
    udp = bytes(dpkt.ip.IP(src=b"\x0a\0\0\x02", dst=b"\x0a\0\0\x0a", p=17, data=dpkt.udp.UDP(data=b"x")))
    arp = b"\xff" * 12 + b"\x08\x06" + b"\x00" * 28
    data = pcap([(1, 0, ethernet(udp)), (2, 0, arp), (3, 0, ethernet(ip_tcp()))])
    segs, stats = read(tmp_path, data[:-10])  # the last record cut off
    assert segs == [] and stats["not_tcp"] == 2 and stats["truncated"] == 1 and stats["frames"] == 2


@pytest.mark.parametrize("data", [b"", b"GIF89a" + b"\0" * 40, b"\xd4\xc3\xb2\xa1\x02\x00"])
def test_not_a_capture_is_a_usage_error(tmp_path: Path, data: bytes) -> None:
    with pytest.raises(UsageError, match="not a pcap"):
        read(tmp_path, data)


@pytest.mark.parametrize("pads", [[0] * 20, [i % 3 for i in range(20)]], ids=["even", "uneven"])
def test_a_run_of_data_frames_is_found_in_bulk_with_its_payloads(tmp_path: Path, pads: list[int]) -> None:
    packages = [struct.pack(">HBB", 12, ord("U"), 1) + struct.pack(">d", i / 8) for i in range(20)]
    frames = [
        (1000 + i, 0, ethernet(ip_tcp(seq=100 + 12 * i, payload=p), pad=pad))
        for i, (p, pad) in enumerate(zip(packages, pads, strict=True))
    ]
    frames.append((2000, 0, ethernet(ip_tcp(seq=999))))  # not part of the run
    path = tmp_path / "run.pcap"
    path.write_bytes(pcap(frames))
    found = list(items(path))
    run, last = found
    assert isinstance(run, DataRun) and isinstance(last, Segment) and last.seq == 999
    assert run.rows.tobytes() == b"".join(packages) and run.size == 12 and run.seq == 100
    assert run.times.tolist() == [1000.0 + i for i in range(20)] and (run.src, run.dport) == (
        "10.0.0.2",
        30004,
    )
    assert [s.payload for s in segments(path)][:20] == packages  # the same, segment by segment


def _from_fifo(tmp_path: Path, data: bytes, name: str = "pipe") -> tuple[list, dict[str, int]]:
    """segments() of `data` written into a named pipe: a file that cannot be mapped, only read."""
    path = tmp_path / name
    os.mkfifo(path)

    def feed() -> None:
        with open(path, "wb") as f:
            f.write(data)

    writer = threading.Thread(target=feed)
    writer.start()
    stats: dict[str, int] = {}
    seen: list[int] = []
    try:
        found = list(segments(path, stats, seen.append))
    finally:
        writer.join()
    assert seen == sorted(seen) and (seen[-1] == len(data) or "truncated" in stats)  # progress: bytes done
    return found, stats


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
@pytest.mark.parametrize("kind", ["pcap", "pcapng"])
@pytest.mark.parametrize("block", [64, 300, 8 << 20])
def test_blocks_of_a_mapped_file_and_of_a_pipe_give_the_same_frames(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, kind: str, block: int
) -> None:
    """Records cut by a block's end, and records longer than a block, are read whole either way."""
    monkeypatch.setattr(pcapfile, "BLOCK", block)
    payloads = [bytes([i]) * (i * 37 % 400) for i in range(1, 30)]  # some frames longer than a block
    frames = [ethernet(ip_tcp(seq=i, payload=p)) for i, p in enumerate(payloads)]
    if kind == "pcap":
        data = pcap([(i, 0, f) for i, f in enumerate(frames)])
    else:
        head = pcapng()
        data = head + b"".join(block_(f, i) for i, f in enumerate(frames))
    mapped, mapped_stats = read(tmp_path, data)
    seen: list[int] = []
    assert len(list(segments(tmp_path / "capture", {}, seen.append))) == len(mapped)
    assert seen == sorted(seen) and seen[-1] == len(data)  # progress reaches the file's end
    piped, piped_stats = _from_fifo(tmp_path, data)
    extra = 3 if kind == "pcapng" else 0  # the frames of pcapng()'s own blocks come first
    assert [s.payload for s in mapped][extra:] == payloads
    assert [(s.time, s.seq, s.payload) for s in piped] == [(s.time, s.seq, s.payload) for s in mapped]
    assert mapped_stats == piped_stats and "truncated" not in mapped_stats
    cut_mapped, cut_stats = read(tmp_path, data[:-5])  # the last record cut off, both ways
    cut_piped, cut_piped_stats = _from_fifo(tmp_path, data[:-5], "cut")
    assert cut_stats["truncated"] == 1 and len(cut_mapped) == len(mapped) - 1
    assert cut_piped_stats == cut_stats and len(cut_piped) == len(cut_mapped)


def block_(frame: bytes, i: int) -> bytes:
    """An enhanced packet block on interface 0 (Ethernet), `i` microseconds in."""
    return block(6, struct.pack("<IIIII", 0, 0, i, len(frame), len(frame)) + frame)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_a_live_pipe_is_decoded_as_it_comes(tmp_path: Path) -> None:
    """Frames written into a pipe come out before the writer is done (tcpdump -w - | ...)."""
    path = tmp_path / "live"
    os.mkfifo(path)
    data = pcap([(i, 0, ethernet(ip_tcp(seq=i))) for i in range(10)])
    first_seen = threading.Event()
    in_time: list[bool] = []

    def feed() -> None:
        with open(path, "wb") as f:
            f.write(data[: len(data) // 2])
            f.flush()
            in_time.append(first_seen.wait(5))  # the rest only once the first frames came out
            f.write(data[len(data) // 2 :])

    writer = threading.Thread(target=feed)
    writer.start()
    seqs = []
    try:
        for seg in segments(path):
            seqs.append(seg.seq)
            first_seen.set()
    finally:
        first_seen.set()
        writer.join()
    assert seqs == list(range(10))
    assert in_time == [True]  # frames came out while the writer was still writing


def test_cli_decodes_a_capture_piped_to_standard_input(tmp_path: Path) -> None:
    import subprocess
    import sys

    frames = [(i, 0, ethernet(ip_tcp(seq=100 + len(PAYLOAD) * i))) for i in range(5)]  # 5 requests in a row
    data = pcap(frames)
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, "-m", "rtde_spec", "capture", "-", "-o", str(out)],
        input=data,
        capture_output=True,
        timeout=60,
    )
    assert result.returncode == 0, result.stderr.decode()
    assert b"/dev/stdin: 5 frames, 1 connection" in result.stdout and b": 5 packages" in result.stdout
    assert (out / "rtde_setup").is_dir()  # the requests, as a table


def test_a_file_cut_shorter_while_it_is_read_is_an_error_not_a_fault(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(pcapfile, "BLOCK", 256)
    path = tmp_path / "shrinking.pcap"
    path.write_bytes(pcap([(i, 0, ethernet(ip_tcp(seq=i))) for i in range(40)]))
    seen = 0
    with pytest.raises(UsageError, match="got shorter while it was read"):
        for _ in segments(path):
            seen += 1
            if seen == 3:
                with open(path, "r+b") as f:
                    f.truncate(1000)  # another program cuts the capture
    assert seen >= 3


def test_nanosecond_times_are_the_nearest_float_in_pcapng_as_in_pcap(tmp_path: Path) -> None:
    """dumpcap writes pcapng with if_tsresol 9. Its 64-bit count of nanoseconds was scaled as a
    float (past 2**53, rounded before scaling): half the capture times came out one float step
    (238 ns at today's epoch) off the nearest, and off the same frames in a nanosecond pcap."""
    import random
    from fractions import Fraction

    rng = random.Random(3)
    stamps = sorted(1_795_765_736_000_000_000 + rng.randrange(10**12) for _ in range(200))
    frame = ethernet(ip_tcp())
    order = "<"
    shb = block(0x0A0D0D0A, struct.pack(order + "IHHq", 0x1A2B3C4D, 1, 0, -1))
    tsresol = struct.pack(order + "HH", 9, 1) + b"\x09" + b"\x00" * 3 + struct.pack(order + "HH", 0, 0)
    idb = block(1, struct.pack(order + "HHI", 1, 0, 65535) + tsresol)
    epbs = b"".join(
        block(6, struct.pack(order + "IIIII", 0, ns >> 32, ns & 0xFFFFFFFF, len(frame), len(frame)) + frame)
        for ns in stamps
    )
    nearest = [float(Fraction(ns, 10**9)) for ns in stamps]
    from_pcapng, _ = read(tmp_path, shb + idb + epbs)
    assert [s.time for s in from_pcapng] == nearest
    from_pcap, _ = read(tmp_path, pcap([(ns // 10**9, ns % 10**9, frame) for ns in stamps], nano=True))
    assert [s.time for s in from_pcap] == nearest


def test_a_capture_of_more_addresses_than_the_cache_holds_is_read(tmp_path: Path) -> None:
    """Addresses are kept as text in a cache of 65,536 that is cleared when full. When a segment's
    source filled it and its destination then cleared it, the source's text was gone: a KeyError
    traceback ended the run (a scan, or a busy collector's capture: 40,000 segments between random
    addresses)."""
    import random

    rng = random.Random(1)
    records = [pcap([])]  # the file header, then a record per segment
    for i in range(40_000):
        ip = dpkt.ip.IP(src=rng.randbytes(4), dst=rng.randbytes(4), p=6)
        ip.data = dpkt.tcp.TCP(sport=40000, dport=30004, seq=i, flags=dpkt.tcp.TH_SYN)
        frame = ethernet(bytes(ip))
        records.append(struct.pack("<IIII", 1_700_000_000, i, len(frame), len(frame)) + frame)
    segs, _ = read(tmp_path, b"".join(records))
    assert len(segs) == 40_000 and len({s.src for s in segs} | {s.dst for s in segs}) > 65_536
