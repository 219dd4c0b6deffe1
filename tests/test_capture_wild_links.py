"""Captures as real setups write them: a 4-tuple reused by a new connection, FCS flags in a
pcap header, older QinQ tags, keep-alive probes. Each decodes to the rows that were sent."""

from __future__ import annotations

import itertools
import struct
from pathlib import Path

import dpkt
import pytest

from rtde_spec.capture.decoder import capture_tables, decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import ACK, Conversation, rtde_packages, rtde_setup, write

CLIENT, SERVER = ("10.0.0.2", 51000), ("10.0.0.10", 30004)
BIG = ("timestamp", "actual_q", "robot_mode", "actual_TCP_pose")


def _close(conv: Conversation) -> None:
    conv.time += 0.01
    for side in ("client", "server"):
        conv.frames.append((conv.time, conv._frame(side, conv.seq[side], b"", dpkt.tcp.TH_FIN | ACK)))


def test_a_new_connection_on_the_4_tuple_of_a_closed_one_is_decoded_as_its_own(tmp_path: Path) -> None:
    """A client that binds its port reconnects 1 s after closing: the new SYN went to the old
    connection (still lingering 5 s for retransmissions), which was then finished 5 s after the
    old FIN in the middle of the new one; the rest came as a stream without its setup: 1,006 of
    3,000 packages dropped as 'without a recipe' (exit 3)."""
    first = Conversation(CLIENT, SERVER)
    rtde_setup(first)
    for package in rtde_packages(50):
        first.send("server", package)
    _close(first)
    second = Conversation(CLIENT, SERVER, time=first.time + 1.0, seq={"client": 900_000, "server": 700_000})
    rtde_setup(second, BIG)
    for package in rtde_packages(3000, BIG):
        second.send("server", package)
        second.frames.append((second.time, second._frame("client", second.seq["client"], b"", ACK)))
    sink = ArrowSink()
    summary = decode_capture(write(tmp_path / "reuse.pcap", [first, second]), sink)
    tables = sink.tables()
    assert summary.problems() == []
    assert [c.packages for c in summary.connections] == [56, 3006]
    assert tables["rtde_outputs_1"].num_rows == 50
    assert tables["rtde_outputs_2"].num_rows == 3000
    assert tables["rtde_outputs_2"].column("timestamp").to_pylist()[-1] == 2999 * 0.002
    # each connection's rows and summary line under a name of its own: they shared one
    name = "10.0.0.2:51000-10.0.0.10:30004"
    assert [c.name for c in summary.connections] == [name, f"{name} #2"]
    assert set(tables["rtde_outputs_1"].column("connection").to_pylist()) == {name}
    assert set(tables["rtde_outputs_2"].column("connection").to_pylist()) == {f"{name} #2"}
    setup = tables["rtde_setup"].column("connection").to_pylist()
    assert setup.count(name) > 0 and setup.count(f"{name} #2") > 0
    from rtde_spec.capture.protocols.base import server_port  # what the decoders read the port from

    assert server_port(f"{name} #2") == server_port(name) == "30004"


def _rtde(tmp_path: Path, count: int = 100) -> tuple[Conversation, Path]:
    conv = Conversation(CLIENT, SERVER)
    rtde_setup(conv)
    for package in rtde_packages(count):
        conv.send("server", package)
    return conv, write(tmp_path / "plain.pcap", [conv])


def _pcap(path: Path, frames: list[tuple[float, bytes]], linktype: int, snap: int = 65535) -> Path:
    with open(path, "wb") as out:
        out.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, snap, linktype))
        for ts, frame in frames:
            kept = frame[:snap]
            out.write(struct.pack("<IIII", int(ts), round(ts % 1 * 1e6), len(kept), len(frame)) + kept)
    return path


def test_a_pcap_header_that_says_its_frames_end_in_an_fcs_is_read_as_its_link_type(tmp_path: Path) -> None:
    """libpcap's and Wireshark's LT_LINKTYPE is the low 16 bits; the top bits say an FCS of so many
    16-bit words ends each frame (0x24000001: Ethernet with 4 bytes). Only the top 4 bits were
    masked: every frame was 'link type 67108865, which this reader does not decode', no rows."""
    conv, plain = _rtde(tmp_path)
    with_fcs = [(ts, frame + b"\xde\xad\xbe\xef") for ts, frame in sorted(conv.frames, key=lambda f: f[0])]
    path = _pcap(tmp_path / "fcs.pcap", with_fcs, 0x24000001)
    expected = capture_tables(plain)
    assert expected["rtde_outputs_1"].num_rows == 100
    assert capture_tables(path) == expected


def test_keep_alive_probes_of_an_idle_client_are_no_damage(tmp_path: Path) -> None:
    """A Windows or BSD client idle while the controller streams probes with one byte (a zero) at
    the sequence number before its next one; Wireshark calls that "TCP Keep-Alive". It was
    compared with the client's last byte sent and counted as a retransmission with other
    bytes: the capture was 'damaged', exit 3."""
    conv = Conversation(CLIENT, SERVER)
    rtde_setup(conv)
    for i, package in enumerate(rtde_packages(100)):
        conv.send("server", package)
        if i % 25 == 0:
            conv.frames.append((conv.time, conv._frame("client", conv.seq["client"] - 1, b"\0", ACK)))
    sink = ArrowSink()
    summary = decode_capture(write(tmp_path / "keepalive.pcap", [conv]), sink)
    assert summary.problems() == []
    assert sink.tables()["rtde_outputs_1"].num_rows == 100


def test_frames_with_the_older_qinq_tag_0x9100_are_read(tmp_path: Path) -> None:
    """Switches from before 802.1ad tag the outer VLAN 0x9100 (Wireshark's default QinQ type):
    every such frame was 'not TCP': no rows, and the run said the capture held no TCP segments."""
    conv, plain = _rtde(tmp_path)
    tagged = [
        (ts, frame[:12] + b"\x91\x00\x00\x05\x81\x00\x00\x07" + frame[12:])
        for ts, frame in sorted(conv.frames, key=lambda f: f[0])
    ]
    expected = capture_tables(plain)
    assert expected["rtde_outputs_1"].num_rows == 100
    assert capture_tables(_pcap(tmp_path / "qinq.pcap", tagged, 1)) == expected


@pytest.mark.parametrize("kind", ["realtime", "urcl_reverse"])
def test_records_of_a_stream_captured_from_its_middle_keep_their_own_capture_times(
    tmp_path: Path, kind: str
) -> None:
    """A capture started after the connect (no SYN): fixed-size records are held until three in a
    row confirm the offset, and were then all given the time of the segment that confirmed it,
    so the first two real-time messages (or reverse records) were 16 and 8 ms late."""
    from tests.test_capture_driver import realtime_conversation, reverse_conversation

    conv = realtime_conversation() if kind == "realtime" else reverse_conversation()
    data = sorted(conv.frames, key=lambda f: f[0])[2:]  # the handshake not captured
    expected = [ts for ts, _ in data][: 10 if kind == "realtime" else 40]
    conv.frames = data
    rows = capture_tables(write(tmp_path / "mid.pcap", [conv]))[kind]
    assert rows.column("capture_time").to_pylist() == pytest.approx(expected, abs=1e-6)  # pcap: microseconds


def test_ipv6_atomic_fragments_are_read_as_the_whole_packets_they_are(tmp_path: Path) -> None:
    """A host told of a path MTU under 1,280 bytes sends every packet with a fragment header of
    offset 0 and no more fragments (RFC 6946's atomic fragment): the whole packet. Every such
    frame was 'a fragment of an IPv6 TCP segment', counted as undecodable: no rows, exit 3."""
    conv = Conversation(("fd00::2", 51000), ("fd00::10", 30004))
    rtde_setup(conv)
    for package in rtde_packages(100):
        conv.send("server", package)
    plain = write(tmp_path / "plain.pcap", [conv])

    def atomic(frame: bytes) -> bytes:
        ip = bytearray(frame[14:54])
        ip[4:6] = (int.from_bytes(ip[4:6], "big") + 8).to_bytes(2, "big")
        ip[6] = 44  # next header: a fragment header, then TCP
        return frame[:14] + bytes(ip) + bytes([6, 0, 0, 0, 0, 0, 0x12, 0x34]) + frame[54:]

    frames = [(ts, atomic(frame)) for ts, frame in sorted(conv.frames, key=lambda f: f[0])]
    expected = capture_tables(plain)
    assert expected["rtde_outputs_1"].num_rows == 100
    assert capture_tables(_pcap(tmp_path / "atomic.pcap", frames, 1)) == expected


def test_data_in_a_syn_is_the_first_of_its_stream(tmp_path: Path) -> None:
    """A client with TCP Fast Open (RFC 7413) sends its first request in the SYN. Those bytes were
    dropped: the protocol version request lost, the setup decoded as protocol 1 (garbled names)
    and every data package 'without a recipe', exit 3."""
    from rtde_spec import build

    plain = Conversation(CLIENT, SERVER)
    rtde_setup(plain)
    request = build("request_protocol_version", protocol_version=2)
    for package in rtde_packages(50):
        plain.send("server", package)
    (syn_time, _), *rest = sorted(plain.frames, key=lambda f: f[0])
    assert rest[1][1].endswith(request)  # the request, sent after the handshake
    fast = Conversation(CLIENT, SERVER)
    fast.frames = [(syn_time, fast._frame("client", 1000, request, dpkt.tcp.TH_SYN)), rest[0], *rest[2:]]
    sink = ArrowSink()
    summary = decode_capture(write(tmp_path / "fast_open.pcap", [fast]), sink)
    assert summary.problems() == []
    got, expected = sink.tables(), capture_tables(write(tmp_path / "plain.pcap", [plain]))
    assert got["rtde_outputs_1"] == expected["rtde_outputs_1"]
    setup = [t["rtde_setup"].drop_columns("capture_time") for t in (got, expected)]
    assert setup[0] == setup[1]  # the request's time is the SYN's


def test_dashboard_rows_after_a_greeting_cut_by_the_snap_length_pair_each_request_with_its_reply(
    tmp_path: Path,
) -> None:
    """tcpdump -s 96 (an old default) keeps 42 bytes of payload here: the greeting (45) is cut,
    the replies are whole. The line after the gap was passed over as the tail of the cut one:
    'power on' got the reply to the next request, and so on to the last (latencies of 0.1 s)."""
    from tests.test_capture_driver import dashboard_conversation

    conv = dashboard_conversation()
    frames = sorted(conv.frames, key=lambda f: f[0])
    whole = capture_tables(_pcap(tmp_path / "whole.pcap", frames, 1))["dashboard"].to_pylist()
    cut = capture_tables(_pcap(tmp_path / "cut.pcap", frames, 1, snap=96))["dashboard"].to_pylist()
    assert whole[0]["outcome"] == "greeting" and len(whole) == 7
    assert str(cut) == str(whole[1:])  # the greeting's row is lost with its end; the rest as sent (nan too)


def test_dashboard_requests_whose_replies_a_gap_lost_have_no_reply_and_the_rest_keep_theirs(
    tmp_path: Path,
) -> None:
    """The segment of the reply to 'load' is not in the capture: 'load' took the reply to 'play',
    'play' the one to 'robotmode', and so on, each with the next one's latency."""
    from tests.test_capture_driver import dashboard_conversation

    conv = dashboard_conversation()
    frames = sorted(conv.frames, key=lambda f: f[0])
    whole = capture_tables(_pcap(tmp_path / "whole.pcap", frames, 1))["dashboard"].to_pylist()
    lost = [f for f in frames if b"File not found" not in f[1]]
    assert len(lost) == len(frames) - 1
    rows = capture_tables(_pcap(tmp_path / "lost.pcap", lost, 1))["dashboard"].to_pylist()
    assert [r["request"] for r in rows] == [r["request"] for r in whole]
    assert rows[2]["outcome"] == "no_reply" and whole[2]["reply"].startswith("File not found")
    assert str(rows[:2] + rows[3:]) == str(whole[:2] + whole[3:])


def test_an_interface_time_offset_is_added_to_its_timestamps(tmp_path: Path) -> None:
    """pcapng's if_tsoffset is "an offset (in seconds) that must be added to the timestamp of each
    packet to obtain the absolute timestamp"; it was ignored: every capture time an hour early."""
    conv, plain = _rtde(tmp_path)

    def block(kind: int, body: bytes) -> bytes:
        body += b"\0" * (-len(body) % 4)
        return struct.pack("<II", kind, len(body) + 12) + body + struct.pack("<I", len(body) + 12)

    offset = struct.pack("<HHq", 14, 8, 3600) + struct.pack("<HH", 0, 0)
    data = block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
    data += block(1, struct.pack("<HHI", 1, 0, 0) + offset)
    for ts, frame in sorted(conv.frames, key=lambda f: f[0]):
        stamp = round(ts * 1e6) - 3600 * 10**6
        head = struct.pack("<IIIII", 0, stamp >> 32, stamp & 0xFFFFFFFF, len(frame), len(frame))
        data += block(6, head + frame)
    shifted = tmp_path / "offset.pcapng"
    shifted.write_bytes(data)
    expected = capture_tables(plain)
    assert expected["rtde_outputs_1"].num_rows == 100
    got = capture_tables(shifted)
    times = [t["rtde_outputs_1"].column("capture_time").to_pylist() for t in (got, expected)]
    assert times[0] == pytest.approx(times[1], abs=5e-6)  # microseconds rounded, not cut as dpkt does
    assert got["rtde_outputs_1"].drop_columns("capture_time") == expected["rtde_outputs_1"].drop_columns(
        "capture_time"
    )


def test_apple_pktap_frames_are_read_through_their_header(tmp_path: Path) -> None:
    """Link type 258, Apple's PKTAP (a capture through macOS's pktap interface that keeps its
    headers; tcpdump and Wireshark read it): a header (its length, 1 for 'a packet follows', the
    packet's link type, the interface and process) before each frame. Every frame was of 'link
    type 258, which this reader does not decode'."""
    conv, plain = _rtde(tmp_path)

    def pktap(frame: bytes) -> bytes:
        header = struct.pack("<III24s", 108, 1, 1, b"en0").ljust(108, b"\0")
        return header + frame

    frames = [(ts, pktap(frame)) for ts, frame in sorted(conv.frames, key=lambda f: f[0])]
    frames.insert(3, (frames[3][0], struct.pack("<III", 108, 2, 1).ljust(108, b"\0")))  # no packet after it
    expected = capture_tables(plain)
    assert expected["rtde_outputs_1"].num_rows == 100
    assert capture_tables(_pcap(tmp_path / "pktap.pcap", frames, 258)) == expected


def test_fragments_seen_on_two_interfaces_are_copies_not_lost_fragments(tmp_path: Path) -> None:
    """`dumpcap -i any -i eth0` records every frame twice. For fragmented datagrams the second copy
    of the last fragment came after the datagram was put together and began a new one, which
    never completed: '102 IPv4 fragments of datagrams whose other fragments never came', exit 3."""
    conv, plain = _rtde(tmp_path)
    frames = []
    for n, (ts, frame) in enumerate(sorted(conv.frames, key=lambda f: f[0])):
        ip, data = frame[14:34], frame[34:]
        cuts = [0, 24, len(data)] if len(data) > 40 else [0, len(data)]
        for a, b in itertools.pairwise(cuts):
            head = bytearray(ip)
            head[2:4], head[4:6] = (20 + b - a).to_bytes(2, "big"), n.to_bytes(2, "big")
            head[6:8] = ((0x2000 if b < len(data) else 0) | a // 8).to_bytes(2, "big")
            frames += [(ts, frame[:14] + bytes(head) + data[a:b])] * 2  # the same frame from two interfaces
    sink = ArrowSink()
    summary = decode_capture(_pcap(tmp_path / "twice.pcap", frames, 1), sink)
    assert summary.problems() == []
    assert summary.reading["ip_reassembled"] == 102  # 100 data packages, 2 setup packages over 40 bytes
    assert sink.tables() == capture_tables(plain)


class Acked(Conversation):
    """A conversation whose segments acknowledge what the other side sent, as real ones do."""

    def _frame(self, side: str, seq: int, payload: bytes, flags: int) -> bytes:
        frame = bytearray(super()._frame(side, seq, payload, flags))
        other = self.seq["server" if side == "client" else "client"]
        frame[14 + 20 + 8 : 14 + 20 + 12] = (other % (1 << 32)).to_bytes(4, "big")
        return bytes(frame)  # the TCP checksum is not checked by the reader


def test_a_request_the_capture_missed_but_the_server_acknowledged_costs_only_its_own_row(
    tmp_path: Path,
) -> None:
    """dumpcap dropped the segment of 'load' (the server got it: its reply acknowledges it). The
    requests after it waited behind the hole for its retransmission, which never comes, until the
    end of the capture: every reply after it was 'unrequested' and every request 'no_reply'."""
    from tests.test_capture_driver import PC, ROBOT

    conv = Acked((PC, 41999), (ROBOT, 29999))
    conv.handshake()
    conv.send("server", b"Connected: Universal Robots Dashboard Server\n")
    pairs = [(b"power on\n", b"Powering on\n"), (b"load x.urp\n", b"File not found: x.urp\n"),
             (b"play\n", b"Failed to execute: play\n"), (b"robotmode\n", b"Robotmode: IDLE\n")]  # fmt: skip
    for request, reply in pairs:
        conv.send("client", request, dt=0.1, keep=request != b"load x.urp\n")
        conv.send("server", reply, dt=0.004)
    rows = capture_tables(write(tmp_path / "dropped.pcap", [conv]))["dashboard"].to_pylist()
    assert [(r["request"], r["reply"], r["outcome"]) for r in rows] == [
        ("", "Connected: Universal Robots Dashboard Server", "greeting"),
        ("power on", "Powering on", "ok"),
        ("", "File not found: x.urp", "unrequested"),
        ("play", "Failed to execute: play", "failed"),
        ("robotmode", "Robotmode: IDLE", "ok"),
    ]


def test_a_segment_only_the_second_capture_point_holds_fills_its_hole_after_the_acknowledgment(
    tmp_path: Path,
) -> None:
    """Two capture points merged (every frame twice, the second 5 ms later), the first missing three
    data segments: the acknowledgment (from the first) comes before the second point's copy, which
    must still fill the hole. A connection that shows copies does not take holes for lost on an ACK."""
    conv = Acked(CLIENT, SERVER)
    rtde_setup(conv)
    for package in rtde_packages(200):
        conv.send("server", package)
        conv.send("client", b"", dt=0.0005)  # the client's ACK of it
    first = sorted(conv.frames, key=lambda f: f[0])
    missing = {first[k][1] for k in (40, 100, 160)}
    assert all(len(frame) > 100 for frame in missing)  # data segments, not ACKs
    merged = [f for f in first if f[1] not in missing] + [(ts + 0.005, frame) for ts, frame in first]
    sink = ArrowSink()
    summary = decode_capture(_pcap(tmp_path / "merged.pcap", sorted(merged, key=lambda f: f[0]), 1), sink)
    assert summary.problems() == []
    assert sink.tables()["rtde_outputs_1"].num_rows == 200
