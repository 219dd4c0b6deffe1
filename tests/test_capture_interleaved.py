"""Runs over what comes between: a control session's inputs between its outputs, and other
connections' packages between a connection's own.

ur_rtde's control interface and URCL's RTDE writer send input packages at 500 Hz on the
connection that streams their outputs, and a client usually holds a second connection (the
receive interface) beside it. Runs of data packages used to end at any data package that was
not the run's next, so such captures were read frame by frame: 50,000 outputs with 50,000
inputs between them took 2.2 s against 0.45 s for the outputs alone. The tables must be those
of the frame-by-frame reading (every run replayed segment by segment), row for row within
each connection.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import dpkt
import pytest

from rtde_spec import build
from rtde_spec.capture.decoder import capture_tables, decode_capture
from rtde_spec.capture.protocols.rtde import RtdeConnection
from rtde_spec.capture.reading import bulk, pcapfile
from rtde_spec.capture.reading.packets import segments
from rtde_spec.capture.runs import Batcher
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import (
    COUNT,
    SMALL,
    Conversation,
    _control_session,
    _input,
    _output,
    control_capture,
    frame_by_frame,
    rtde_packages,
    rtde_setup,
    same_rows_per_connection,
    write,
)


def _with_and_without_runs(
    path: Path, monkeypatch: pytest.MonkeyPatch
) -> tuple[dict[str, Any], dict[str, Any], int]:
    """The tables read with runs, and one frame at a time; and how many packages runs carried."""

    carried: list[int] = []
    feed_run = RtdeConnection.feed_run
    with monkeypatch.context() as patch:
        patch.setattr(
            RtdeConnection,
            "feed_run",
            lambda s, a, c, r, t: (carried.append(len(t)), feed_run(s, a, c, r, t)),
        )
        with_runs = capture_tables(path)
    with monkeypatch.context() as patch:
        frame_by_frame(patch)
        one_by_one = capture_tables(path)
    return with_runs, one_by_one, sum(carried)


def _same_both_ways(path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[dict[str, Any], list[Any]]:
    """The tables and connection summaries read with runs, checked equal to the frame-by-frame
    reading's (rows within each connection, summaries whole)."""
    read = []
    for runs in (True, False):
        with monkeypatch.context() as patch:
            if not runs:
                frame_by_frame(patch)
            sink = ArrowSink()
            summary = decode_capture(path, sink)
        read.append((sink.tables(), sorted(summary.connections, key=lambda c: c.name)))
    (tables, connections), (reference, reference_connections) = read
    same_rows_per_connection(tables, reference)
    assert connections == reference_connections
    return tables, connections


@pytest.mark.parametrize("acks", [False, True])
def test_a_control_sessions_outputs_and_inputs_are_read_as_two_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, acks: bool
) -> None:
    path = control_capture(tmp_path / "control.pcap", acks=acks)
    with_runs, one_by_one, carried = _with_and_without_runs(path, monkeypatch)
    same_rows_per_connection(with_runs, one_by_one)
    outputs, inputs = with_runs["rtde_outputs_1"].to_pylist(), with_runs["rtde_inputs_1"].to_pylist()
    assert [round(r["timestamp"] / 0.002) for r in outputs] == list(range(COUNT))
    assert [r["input_int_register_24"] for r in inputs] == list(range(COUNT))
    assert carried >= 2 * COUNT - 10, f"runs carried {carried} of {2 * COUNT} packages"  # before: 0


@pytest.mark.parametrize("clients", [1, 2, 12])  # 12: more directions than runs held (the oldest flushed)
def test_frames_read_one_by_one_batch_each_direction_of_a_control_session(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, clients: int
) -> None:
    """IPv6 frames are read one by one (`capture/runs.Batcher`): there too each direction of
    each connection is batched over the other's packages. Before: no batch at all."""
    path = control_capture(tmp_path / "v6.pcap", acks=True, clients=clients, v6=True)
    with_runs, one_by_one, carried = _with_and_without_runs(path, monkeypatch)
    same_rows_per_connection(with_runs, one_by_one)
    assert with_runs["rtde_inputs_1"].num_rows == clients * COUNT
    if clients <= Batcher.HELD // 2:
        assert carried >= 2 * clients * COUNT - 20 * clients, f"runs carried {carried}"


def test_two_connections_interleaved_package_by_package_each_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """ur_rtde's receive and control interfaces side by side: four streams, each its own run."""
    path = control_capture(tmp_path / "two.pcap", acks=True, clients=2)
    with_runs, one_by_one, carried = _with_and_without_runs(path, monkeypatch)
    same_rows_per_connection(with_runs, one_by_one)
    assert with_runs["rtde_outputs_1"].num_rows == 2 * COUNT
    assert carried >= 4 * COUNT - 20


def _found(path: Path) -> tuple[Any, list[bulk.Found]]:
    (records,) = list(pcapfile.blocks(open(path, "rb"), str(path), {}))
    return records, bulk.runs(records)


def _arp(conv: Conversation) -> None:
    frame = dpkt.ethernet.Ethernet(
        src=b"\x02" * 6, dst=b"\xff" * 6, type=dpkt.ethernet.ETH_TYPE_ARP, data=b"\0" * 28
    )
    conv.time += 0.0001
    conv.frames.append((conv.time, bytes(frame)))


def _text(conv: Conversation) -> None:
    conv.send("client", build("text_message", message="hello", source="test", warning_level=1), dt=0.0001)


@pytest.mark.parametrize("between", [_arp, _text])
def test_a_control_message_of_the_connection_or_a_frame_not_read_as_tcp_ends_its_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, between: Callable[[Conversation], None]
) -> None:
    """A text message from the client (its connection's state may change) and an ARP frame
    (not read here as TCP: it could have been a fragment of the connection) each end every run
    spanning it; the tables are those of the frame-by-frame reading."""
    path = control_capture(tmp_path / "broken.pcap", between={100: between})
    records, found = _found(path)
    frames, buf = records.offsets.tolist(), records.buf
    ends = [
        k
        for k in range(len(frames))
        if buf[frames[k] + 12 : frames[k] + 14] == b"\x08\x06"
        or b"hello" in buf[frames[k] : frames[k] + records.lengths[k]]
    ]
    assert len(ends) == 1
    assert len(found) >= 4 and all(not first < ends[0] < end for first, end, _, _ in found)
    with_runs, one_by_one, _ = _with_and_without_runs(path, monkeypatch)
    same_rows_per_connection(with_runs, one_by_one)


def test_segments_stay_in_file_order_with_runs_interleaved(tmp_path: Path) -> None:
    """`segments()` gives every segment in the file's order (runs expanded in their places)."""
    path = control_capture(tmp_path / "order.pcap", acks=True, clients=2)
    ours = [(s.src, s.sport, s.seq, s.payload) for s in segments(path)]
    theirs = []
    for _, frame in dpkt.pcap.Reader(open(path, "rb")):
        ip = dpkt.ethernet.Ethernet(frame).data
        tcp = ip.data
        theirs.append((".".join(str(b) for b in ip.src), tcp.sport, tcp.seq, bytes(tcp.data)))
    assert ours == theirs


def test_recipe_tables_are_numbered_in_the_order_their_first_packages_come(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`rtde_outputs_1` is the first recipe met, whether its packages come in a run or one by one:
    ten packages of one client's recipe (too few for a run), then a second client's stream."""
    first, second = ("timestamp", "actual_q", "robot_mode"), ("timestamp", "actual_TCP_pose")
    a = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    b = Conversation(("10.0.0.3", 51001), ("10.0.0.10", 30004), time=1_700_000_000.5)
    rtde_setup(a, first)
    for package in rtde_packages(10, first):
        a.send("server", package)
    rtde_setup(b, second)
    for package in rtde_packages(100, second):
        b.send("server", package)
    path = write(tmp_path / "two.pcap", [a, b])
    with_runs, one_by_one, carried = _with_and_without_runs(path, monkeypatch)
    assert carried >= 90  # the second client's stream came as a run
    same_rows_per_connection(with_runs, one_by_one)
    assert "actual_q_0" in with_runs["rtde_outputs_1"].column_names
    assert "actual_TCP_pose_0" in with_runs["rtde_outputs_2"].column_names


@pytest.mark.parametrize("late", [False, True])
def test_a_hole_the_peer_acknowledged_is_lost_where_the_acknowledgment_is(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, late: bool
) -> None:
    """One of a control client's inputs is not in the capture; the controller's next outputs
    acknowledge past it. Frame by frame the hole is lost at that acknowledgment, and a copy of
    the input coming later (a spurious retransmission: `late`) is a copy of given-up bytes. The
    outputs' runs carry those acknowledgments: read in bulk, the hole must be lost there too."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004), acking=True)
    outputs, writes = _control_session(conv)
    missing = b""
    for i in range(60):
        conv.send("server", _output(outputs, i))
        _, frame = conv.send("client", _input(writes, i), keep=i != 5)
        missing = frame if i == 5 else missing
    if late:
        conv.resend(missing, dt=0.5)
    tables, connections = _same_both_ways(write(tmp_path / "hole.pcap", [conv]), monkeypatch)
    inputs = [r["input_int_register_24"] for r in tables["rtde_inputs_1"].to_pylist()]
    assert inputs == [i for i in range(60) if i != 5]
    (connection,) = connections
    assert (connection.gaps, connection.lost_bytes) == (1, len(_input(writes, 5)))


def test_runs_held_for_frames_read_one_by_one_keep_the_order_recipes_are_met_in(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """IPv6 frames are read one by one and runs held per connection direction: the second
    client's run, ended by its text message, was written (and its table named) before the first
    client's still held, whose first package came first."""
    first, second = ("timestamp", "actual_q", "robot_mode"), ("timestamp", "actual_TCP_pose")
    a = Conversation(("fd00::2", 51000), ("fd00::10", 30004))
    b = Conversation(("fd00::3", 51001), ("fd00::10", 30004), time=a.time + 0.0001)
    rtde_setup(a, first)
    rtde_setup(b, second)
    for one, two in zip(rtde_packages(40, first), rtde_packages(40, second), strict=True):
        for conv, package in ((a, one), (b, two)):
            conv.time = max(a.time, b.time) + 0.0001  # one clock: the file keeps this order
            conv.send("server", package)
    b.send("server", build("text_message", message="hello", source="test", warning_level=1))
    path = write(tmp_path / "two6.pcap", [a, b])
    with_runs, one_by_one, carried = _with_and_without_runs(path, monkeypatch)
    assert carried >= 60  # both clients' packages came in (held) runs
    same_rows_per_connection(with_runs, one_by_one)
    assert "actual_q_0" in with_runs["rtde_outputs_1"].column_names
    assert "actual_TCP_pose_0" in with_runs["rtde_outputs_2"].column_names


@pytest.mark.parametrize("case", ["idle", "closed"])
def test_connections_are_finished_at_the_same_capture_time_inside_another_connections_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, case: str
) -> None:
    """Connections are finished by capture time (idle 900 s, or 5 s after their FIN), looked at
    between segments. A run of another connection read in bulk spans that time, and the first
    connection's next segments inside its span are read after it: they went on in the finished
    connection, where frame by frame they begin a new one."""
    a = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    b = Conversation(("10.0.0.3", 51001), ("10.0.0.10", 30004), time=a.time + 0.0001)
    rtde_setup(a, SMALL)
    rtde_setup(b, ("timestamp", "actual_TCP_pose"))
    first = rtde_packages(10, SMALL)
    last = b""
    for package in first[:5]:
        _, last = a.send("server", package)
    if case == "closed":
        a.time += 0.001
        a.frames.append((a.time, a.fin("server")))
    step = 100.0 if case == "idle" else 0.5
    for i, package in enumerate(rtde_packages(30, ("timestamp", "actual_TCP_pose"))):
        b.send("server", package, dt=step)
        if i == 14:  # A again, inside B's run: after 1,500 s silent, or 7.5 s after its FIN
            a.time = b.time
            if case == "idle":
                for again in first[5:]:
                    a.send("server", again)
            else:  # a late copy of its last package
                a.resend(last)
    _, connections = _same_both_ways(write(tmp_path / "finished.pcap", [a, b]), monkeypatch)
    assert len(connections) == 3  # A, A's segments after it was finished, B
