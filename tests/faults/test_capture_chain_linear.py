"""After a TCP gap, the RTDE/primary framing looks for the first header whose chain of headers
leads onto a package it can vouch for. Every offset before that package was walked along its
chain again: held bytes that are all short plausible headers (RTDE start packages, 3 bytes),
one byte short of the data package, cost the square of their length (24 kB: 24 s; a 64 kB
window: minutes, per gap). The work is counted, not timed."""

from __future__ import annotations

from pathlib import Path

import pytest

import rtde_spec.capture.framing.sized as framing
from rtde_spec.capture.decoder import decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from tests.capture_files import Conversation, rtde_packages, rtde_setup, write
from tests.faults.test_capture_ports_linear import counted


def chained(path: Path, size: int) -> Path:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    packages = rtde_packages(30)
    for package in packages[:10]:
        conv.send("server", package)
    conv.send("server", packages[10], keep=False)  # lost: the framing searches from here
    chain = b"\x00\x03S" * (size // 3) + b"\xff"  # start packages that miss the data package by one
    for i in range(0, len(chain), 1400):
        conv.send("server", chain[i : i + 1400])
    for package in packages[11:]:
        conv.send("server", package)
    return write(path, [conv])


def test_headers_chained_before_the_package_found_are_each_looked_at_a_bounded_number_of_times(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    per_byte = []
    for size in (3000, 12000):
        calls = counted(monkeypatch, framing.Framing, "plausible")
        sink = ArrowSink()
        summary = decode_capture(chained(tmp_path / f"chain{size}.pcap", size), sink)
        assert sink.tables()["rtde_outputs_1"].num_rows == 29
        (connection,) = summary.connections
        assert connection.skipped_bytes == size + 1 and connection.gaps == 1
        per_byte.append(calls[0] / size)
        monkeypatch.undo()
    assert per_byte[1] < 8 and per_byte[1] < per_byte[0] * 1.5, per_byte
