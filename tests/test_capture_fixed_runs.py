"""URCL's external control in runs: the driver's reverse interface writes a fixed-size record
every 2 ms (no header), beside RTDE at 500 Hz. Those records were read frame by frame (parsed,
routed, reassembled and framed one at a time); runs of them (one record a segment, in order,
only the connection's ACKs between) now go to the connection's decoder whole
(`ExternalConnection.feed_rows`). The tables must be those of the frame-by-frame reading.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.capture.decoder import capture_tables, decode_capture
from rtde_spec.capture.protocols.external import ExternalConnection
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import Conversation, frame_by_frame, rtde_raw_setup, same_rows_per_connection, write

ROBOT, PC = "192.168.56.101", "192.168.56.1"
STEPS = 600
PROGRAM = b"\n".join(
    [b"# HEADER_BEGIN", b"MULT_jointstate = 1000000", b"read_timeout = params_mult[1] / 1000.0"]
    + [b"# line %d" % i for i in range(50)]
    + [b"# NODE_CONTROL_LOOP_ENDS", b""]
)


def words(*values: int) -> bytes:
    return struct.pack(f">{len(values)}i", *values)


def driver_session(path: Path, *, program: bool, lose: int | None = None, acks: bool = True) -> Path:
    """The robot fetches the program (when `program`), then the driver's reverse records and the
    controller's RTDE packages take turns every 2 ms; the robot ACKs the records (`acks`);
    the record numbered `lose` is not in the capture."""
    convs = []
    if program:
        sender = Conversation((ROBOT, 40002), (PC, 50002), time=1_699_999_999.0)
        sender.handshake()
        sender.send("client", b"request_program\n")
        sender.send("server", PROGRAM, dt=0.001)
        convs.append(sender)
    reverse = Conversation((ROBOT, 40001), (PC, 50001))
    rtde = Conversation((PC, 42004), (ROBOT, 30004))
    for conv in (reverse, rtde):
        conv.handshake()
    rtde_raw_setup(rtde)
    for step in range(STEPS):
        q = [step * 1000 + j for j in range(6)]
        reverse.time = rtde.time = max(reverse.time, rtde.time)  # one clock: the file keeps this order
        reverse.send("server", words(20, *q, 1), dt=0.001, keep=step != lose)  # SERVOJ
        if acks:
            reverse.time += 0.0001
            reverse.frames.append((reverse.time, reverse.bare("client")))
        t = step * 0.002
        rtde.send("server", struct.pack(">HBBd6d", 60, ord("U"), 1, t, *(x / 1e6 for x in q)), dt=0.001)
    return write(path, [*convs, reverse, rtde])


def _read(path: Path, monkeypatch: pytest.MonkeyPatch, runs: bool) -> tuple[dict[str, Any], Any, int]:
    """The tables and summary, read with runs or frame by frame; records the runs carried."""

    carried: list[int] = []
    with monkeypatch.context() as patch:
        if runs:
            feed_rows = ExternalConnection.feed_rows

            def counted(self: ExternalConnection, sender: str, rows: Any, times: Any) -> bool:
                carried.append(len(rows))
                return feed_rows(self, sender, rows, times)

            patch.setattr(ExternalConnection, "feed_rows", counted)
        else:
            frame_by_frame(patch)
        sink = ArrowSink()
        summary = decode_capture(path, sink)
    return sink.tables(), summary, sum(carried)


def _connections(summary: Any) -> list[Any]:
    return sorted(summary.connections, key=lambda c: c.name)


@pytest.mark.parametrize("program", [True, False])  # the layout known from the program, or chosen at the end
def test_the_reverse_interfaces_records_are_read_in_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, program: bool
) -> None:
    path = driver_session(tmp_path / "driver.pcap", program=program)
    tables, summary, carried = _read(path, monkeypatch, runs=True)
    one_by_one, one_summary, _ = _read(path, monkeypatch, runs=False)
    same_rows_per_connection(tables, one_by_one)
    assert tables["urcl_reverse"].num_rows == STEPS
    assert [r["target_0"] for r in tables["urcl_reverse"].to_pylist()] == pytest.approx(
        [step * 1000 / 1e6 for step in range(STEPS)]
    )
    assert carried >= STEPS - 40, f"runs carried {carried} of {STEPS} records"  # before: none
    assert _connections(summary) == _connections(one_summary)  # counts, the layout chosen and why


def test_a_lost_record_ends_the_run_and_is_counted_as_before(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = driver_session(tmp_path / "lost.pcap", program=True, lose=300)
    tables, summary, carried = _read(path, monkeypatch, runs=True)
    one_by_one, one_summary, _ = _read(path, monkeypatch, runs=False)
    same_rows_per_connection(tables, one_by_one)
    assert tables["urcl_reverse"].num_rows == STEPS - 1
    assert _connections(summary) == _connections(one_summary)
    reverse = next(c for c in summary.connections if c.kind == "urcl-reverse")
    assert (reverse.gaps, reverse.lost_bytes) == (1, 32)
    assert carried >= 290  # the records before the gap; after it, the rest of the block one by one


def test_the_ports_of_a_port_map_are_read_in_runs(tmp_path: Path) -> None:
    """The reverse interface on another port (`--port-map 50011=reverse`): runs there too."""
    path = driver_session(tmp_path / "driver.pcap", program=True)
    data = path.read_bytes().replace(struct.pack(">H", 50001), struct.pack(">H", 50011))
    moved = tmp_path / "moved.pcap"
    moved.write_bytes(data)  # TCP checksums are not checked by the reader
    tables = capture_tables(moved, port_map={50011: "reverse"})
    assert tables["urcl_reverse"].num_rows == STEPS


def test_the_real_time_interfaces_messages_are_read_in_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Port 30003 at 500 Hz (python-urx's and older clients' stream): one size a connection."""
    from rtde_spec.capture.protocols.realtime import RealtimeConnection

    conv = Conversation((PC, 43003), (ROBOT, 30003))
    conv.handshake()
    body = bytearray(1116)
    struct.pack_into(">i", body, 0, 1116)
    for step in range(STEPS):
        struct.pack_into(">d6d", body, 4, step * 0.002, *(step / 1000 + j for j in range(6)))
        conv.send("server", bytes(body))
        conv.frames.append((conv.time + 0.0001, conv.bare("client")))
    path = write(tmp_path / "realtime.pcap", [conv])
    carried: list[int] = []
    feed_rows = RealtimeConnection.feed_rows

    def counted(self: RealtimeConnection, sender: str, rows: Any, times: Any) -> bool:
        carried.append(len(rows))
        return feed_rows(self, sender, rows, times)

    monkeypatch.setattr(RealtimeConnection, "feed_rows", counted)
    tables, summary, _ = _read(path, monkeypatch, runs=True)
    one_by_one, one_summary, _ = _read(path, monkeypatch, runs=False)
    same_rows_per_connection(tables, one_by_one)
    assert _connections(summary) == _connections(one_summary)
    rows = tables["realtime"].to_pylist()
    assert len(rows) == STEPS and rows[-1]["time"] == pytest.approx((STEPS - 1) * 0.002)
    assert sum(carried) >= STEPS - 40, f"runs carried {sum(carried)} of {STEPS}"
