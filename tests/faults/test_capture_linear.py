"""Captures that are not linear (issue 31.3 and 31.7): holes, floods, streams without an end.

Reassembly costs the same per segment whatever the pattern of holes; a stream past a
decoder's bound is cut, counted and reported (exit 3), never dropped silently; state
of finished, foreign and half-open connections is freed; differences between copies of
the same bytes, fragments and setup replies that fit no request are reported.
Timings are relative (a size against four times it, best of three), never absolute:
figures for big inputs are in benchmarks/faults_capture.py.
"""

from __future__ import annotations

import socket
import struct
import sys
import threading
import time
from pathlib import Path

import dpkt
import pytest

import rtde_spec.capture.routing.flows as flows
from rtde_spec import build
from rtde_spec.capture.decoder import capture_tables, decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from rtde_spec.capture.tcp import Direction
from rtde_spec.errors import RecipeError
from rtde_spec.rtde.client import RtdeClient
from tests import capture_files
from tests.helpers import ROOT

sys.path.append(str(ROOT / "benchmarks"))
import hostile_captures


def _holes(count: int) -> float:
    """CPU seconds to reassemble `count` 1-byte segments, each after a 1-byte hole (best of three;
    process time, so other processes on the machine do not count)."""
    best = float("inf")
    for _ in range(3):
        direction = Direction()
        direction.feed(0.0, 999, b"", syn=True)
        start = time.process_time()
        for i in range(count):
            direction.feed(i * 1e-4, 1000 + 2 * i + 1, b"x")
        direction.drain()
        best = min(best, time.process_time() - start)
        assert direction.gaps == count
    return best


def test_reassembly_of_holes_is_linear() -> None:
    small, big = _holes(8000), _holes(32000)
    assert big / small < 8, f"4x the segments took {big / small:.1f}x the time (quadratic is 16x)"


def _tables_and_summary(path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[flows.FlowTable, object]:
    seen: dict[str, flows.FlowTable] = {}
    original = flows.FlowTable.__init__

    def init(self: flows.FlowTable, *args: object, **kwargs: object) -> None:
        original(self, *args, **kwargs)  # type: ignore[arg-type]
        seen["table"] = self

    monkeypatch.setattr(flows.FlowTable, "__init__", init)
    summary = decode_capture(path, ArrowSink())
    return seen["table"], summary


def test_syns_to_ports_nobody_decodes_keep_bounded_state(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(flows, "MAX_PENDING_SYNS", 100)
    table, summary = _tables_and_summary(
        hostile_captures.syn_flood(tmp_path / "scan.pcap", 5000), monkeypatch
    )
    assert len(table.pending) <= 100 and not table.flows and not table.routes
    assert summary.connections == []  # type: ignore[attr-defined]


def test_closed_connections_are_freed_and_still_summarised(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    conversations = []
    for i in range(30):  # one after another, 10 s apart: each closed long before the next
        conv = capture_files.Conversation(("10.0.0.2", 40000 + i), ("10.0.0.10", 30004), time=1.7e9 + 10 * i)
        capture_files.rtde_setup(conv)
        for package in capture_files.rtde_packages(20):
            conv.send("server", package)
        conv.frames.append((conv.time, conv._frame("client", conv.seq["client"], b"", 0x11)))  # FIN
        conversations.append(conv)
    table, summary = _tables_and_summary(
        capture_files.write(tmp_path / "many.pcap", conversations), monkeypatch
    )
    assert len(table.flows) <= 1, "connections closed long ago are still held"
    assert len(summary.connections) == 30  # type: ignore[attr-defined]
    assert summary.packages == 30 * 26  # type: ignore[attr-defined]
    assert summary.problems() == []  # type: ignore[attr-defined]


def test_past_the_listed_connections_the_summary_folds_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(flows, "MAX_LISTED", 5)
    monkeypatch.setattr(flows, "LINGER_SECONDS", 0.0)
    path = hostile_captures.rtde_connections(tmp_path / "conns.pcap", 40)
    _, summary = _tables_and_summary(path, monkeypatch)
    names = [c.name for c in summary.connections]  # type: ignore[attr-defined]
    assert any(name.endswith("more rtde connections") for name in names), names
    assert len(names) < 40
    assert summary.packages == 40 * 10  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("newlines", "says"), [(False, "bytes of robot lines over 4096 bytes cut"), (True, "counted, not kept")]
)
def test_a_script_sender_stream_past_its_bounds_is_cut_and_reported(
    tmp_path: Path, newlines: bool, says: str
) -> None:
    path = hostile_captures.script_stream(tmp_path / "flood.pcap", 300_000, newlines)
    result = capture_files.run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert says in result.stderr and "damaged" in result.stderr


def test_a_retransmission_with_other_bytes_is_a_conflict(tmp_path: Path) -> None:
    conv = capture_files.Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    capture_files.rtde_setup(conv)
    packages = capture_files.rtde_packages(10)
    for package in packages[:5]:
        conv.send("server", package)
    seq = conv.seq["server"] - len(packages[4])
    forged = packages[4][:10] + bytes(len(packages[4]) - 10)  # the same range, other bytes
    frame = conv._frame("server", seq, forged, 0x18)
    conv.resend(frame)
    for package in packages[5:]:
        conv.send("server", package)
    path = capture_files.write(tmp_path / "conflict.pcap", [conv])
    summary = decode_capture(path, ArrowSink())
    assert any("retransmissions with other bytes" in p for p in summary.problems()), summary.problems()
    assert capture_tables(path)["rtde_outputs_1"].num_rows == 10  # the first copy decoded


def test_ipv4_fragments_are_put_back_together(tmp_path: Path) -> None:
    conv = capture_files.Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    capture_files.rtde_setup(conv)
    packages = capture_files.rtde_packages(6)
    for package in packages[:3]:
        conv.send("server", package)
    seq = conv.seq["server"]
    tcp = dpkt.tcp.TCP(sport=30004, dport=51000, seq=seq, flags=0x18, data=b"".join(packages[3:]))
    payload = bytes(tcp)
    cut = 64  # a multiple of 8, inside the TCP data
    for offset, piece, more in ((0, payload[:cut], True), (cut, payload[cut:], False)):
        ip = dpkt.ip.IP(
            src=socket.inet_aton("10.0.0.10"), dst=socket.inet_aton("10.0.0.2"), p=6, id=77, data=piece
        )
        ip.offset, ip.mf = offset // 8, int(more)  # in units of 8 bytes, as on the wire
        eth = dpkt.ethernet.Ethernet(
            src=b"\x02" * 6, dst=b"\x04" * 6, type=dpkt.ethernet.ETH_TYPE_IP, data=ip
        )
        conv.time += 0.001
        conv.frames.append((conv.time, bytes(eth)))
    path = capture_files.write(tmp_path / "fragments.pcap", [conv])
    summary = decode_capture(path, ArrowSink())
    assert summary.reading.get("ip_reassembled") == 1 and summary.reading.get("ip_fragments") == 2
    assert summary.problems() == [], summary.problems()
    assert capture_tables(path)["rtde_outputs_1"].num_rows == 6


def test_a_setup_reply_with_more_types_than_names_is_refused_in_a_capture(tmp_path: Path) -> None:
    conv = capture_files.Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send(
        "client",
        build("setup_outputs_v2", output_frequency=500.0, variable_names=["timestamp", "robot_mode"]),
    )
    conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=["DOUBLE"] * 2000))
    summary = decode_capture(capture_files.write(tmp_path / "types.pcap", [conv]), ArrowSink())
    assert any("expected 2, got 2000" in p for p in summary.problems()), summary.problems()


def test_a_setup_reply_with_more_types_than_names_is_refused_by_the_client() -> None:
    listener = socket.create_server(("127.0.0.1", 0))

    def controller() -> None:
        conn, _ = listener.accept()
        with conn:
            while True:
                head = conn.recv(3, socket.MSG_WAITALL)
                if len(head) < 3:
                    return
                size, kind = struct.unpack(">HB", head)
                conn.recv(size - 3, socket.MSG_WAITALL) if size > 3 else b""
                reply = {
                    ord("V"): build("request_protocol_version_reply", accepted=True),
                    ord("v"): build("get_urcontrol_version_reply", major=5, minor=15, bugfix=0, build=0),
                    ord("O"): build(
                        "setup_outputs_v2_reply", output_recipe_id=1, variable_types=["DOUBLE"] * 2000
                    ),
                }.get(kind)
                if reply is None:
                    return
                conn.sendall(reply)

    threading.Thread(target=controller, daemon=True).start()
    with RtdeClient("127.0.0.1", listener.getsockname()[1], timeout=5) as client:
        with pytest.raises(RecipeError, match="2000 types for the 2 names"):
            client.setup_outputs(["timestamp", "robot_mode"], 125)
    listener.close()
