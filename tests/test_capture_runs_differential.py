"""Runs against the frame-by-frame reading, on random interleavings of the streams a capture of
a real cell holds: a control session (outputs, inputs), a receive session, URCL's reverse
interface and the real-time interface, with the peers' ACKs, control messages, lost and
retransmitted segments. Whatever the order, the tables (row for row within each connection)
and each connection's summary must be those of the reading that takes every frame alone.

Runs now go on over other connections and the other direction (`bulk.runs`, `runs.Batcher`),
and fixed-size records go to their decoders whole (`feed_rows`): this is the check that no
ordering of frames makes them differ.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtde_spec import build
from rtde_spec.capture.decoder import decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import (
    Conversation,
    _control_session,
    _input,
    _output,
    frame_by_frame,
    same_rows_per_connection,
    write,
)

ROBOT, PC = "192.168.56.101", "192.168.56.1"
STREAMS = ("control", "receive", "reverse", "realtime")
RECEIVED = ("timestamp", "actual_TCP_pose", "runtime_state")  # the receive session's recipe
ACTIONS = ("send", "send", "send", "send", "answer", "ack", "message", "lose", "resend")


def _cell() -> dict[str, Any]:
    """The streams; data segments acknowledge what the other side sent (lost segments too, as
    a capture that missed them shows), and the two RTDE sessions have recipes of their own."""
    control = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004), acking=True)
    receive = Conversation(("10.0.0.3", 51001), ("10.0.0.10", 30004), acking=True)
    reverse = Conversation((ROBOT, 40001), (PC, 50001), acking=True)
    realtime = Conversation((PC, 43003), (ROBOT, 30003), acking=True)
    codecs = {"control": _control_session(control), "receive": _control_session(receive, RECEIVED)}
    for conv in (reverse, realtime):
        conv.handshake()
    return {"convs": {"control": control, "receive": receive, "reverse": reverse, "realtime": realtime},
            "codecs": codecs, "n": dict.fromkeys(STREAMS, 0), "lose": set(), "last": {}}  # fmt: skip


def _package(cell: dict[str, Any], stream: str) -> bytes:
    i = cell["n"][stream] = cell["n"][stream] + 1
    if stream in cell["codecs"]:
        return _output(cell["codecs"][stream][0], i)
    if stream == "reverse":
        return struct.pack(">8i", 20, *(i * 1000 + j for j in range(6)), 1)
    body = bytearray(1116)
    struct.pack_into(">id", body, 0, 1116, i * 0.002)
    return bytes(body)


def _step(cell: dict[str, Any], stream: str, action: str) -> None:
    conv: Conversation = cell["convs"][stream]
    conv.time = max(c.time for c in cell["convs"].values())  # one clock: the file keeps this order
    server = "client" if stream == "reverse" else "server"  # the side that streams
    if action == "send":
        keep = stream not in cell["lose"]
        cell["lose"].discard(stream)
        cell["last"][stream] = conv.send(server, _package(cell, stream), dt=0.0005, keep=keep)[1]
    elif action == "answer" and stream in cell["codecs"]:
        keep = stream not in cell["lose"]  # an input lost: the next output acknowledges past it
        cell["lose"].discard(stream)
        conv.send("client", _input(cell["codecs"][stream][1], cell["n"][stream]), dt=0.0005, keep=keep)
    elif action == "ack":
        conv.time += 0.0001
        conv.frames.append((conv.time, conv.bare("server" if server == "client" else "client")))
    elif action == "message" and stream in cell["codecs"]:
        conv.send("client", build("text_message", message="m", source="t", warning_level=1), dt=0.0005)
    elif action == "lose":
        cell["lose"].add(stream)
    elif action == "resend" and stream in cell["last"]:
        conv.resend(cell["last"][stream], dt=0.0005)


def _read(path: Path, monkeypatch: pytest.MonkeyPatch, runs: bool) -> tuple[dict[str, Any], list[Any]]:

    with monkeypatch.context() as patch:
        if not runs:
            frame_by_frame(patch)
        sink = ArrowSink()
        summary = decode_capture(path, sink)
    return sink.tables(), sorted(summary.connections, key=lambda c: c.name)


# long stretches of one stream's packages make runs; the rest interleaves them at random
blocks = st.lists(
    st.tuples(st.sampled_from(STREAMS), st.sampled_from(ACTIONS), st.integers(1, 40)), min_size=4, max_size=30
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(plan=blocks, weave=st.integers(0, 3))
def test_runs_give_the_frame_by_frame_tables_whatever_the_interleaving(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, plan: list[tuple[str, str, int]], weave: int
) -> None:
    cell = _cell()
    for stream, action, times in plan:
        for k in range(times if action in ("send", "ack", "answer") else 1):
            _step(cell, stream, action)
            if weave and k % weave == 0:  # the other streams between
                for other in STREAMS[: weave + 1]:
                    if other != stream:
                        _step(cell, other, "send")
                        _step(cell, other, "ack")
    path = write(tmp_path / "cell.pcap", list(cell["convs"].values()))
    tables, summary = _read(path, monkeypatch, runs=True)
    frames, frame_summary = _read(path, monkeypatch, runs=False)
    assert summary == frame_summary
    same_rows_per_connection(tables, frames)
