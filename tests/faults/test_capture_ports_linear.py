"""Every per-port decoder looks at each byte of a hostile stream a bounded number of times (issue 31.3).

A stream captured from its middle, fed one byte per segment, with no boundary to find
(bytes that are no package): RTDE and primary search for a package header, the
real-time port for its message size, URCL's fixed records for their offset. Each used
to look at everything held again on every segment (RTDE: 8 kB took 63 s; real-time:
20 kB took 146 s and held every byte). The work is counted, not timed: the calls of
the protocol's check per input byte must not grow with the stream's length, and what
was passed over is reported, never dropped with "ok".
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import rtde_spec.capture.framing.sized as framing
import rtde_spec.capture.protocols.realtime as realtime
from rtde_spec.capture.decoder import decode_capture
from rtde_spec.capture.tables.sink import ArrowSink
from rtde_spec.capture.tables.summary import CaptureSummary
from rtde_spec.external.codec import RecordCodec
from tests.helpers import ROOT

sys.path.append(str(ROOT / "benchmarks"))
import hostile_captures as hc


def garbage(size: int) -> bytes:
    """Bytes that hold no package of any of our protocols (a fixed pseudo-random pattern)."""
    return bytes((i * 7919 + 13) % 251 for i in range(size))


def one_byte_segments(path: Path, port: int, data: bytes) -> Path:
    """`data` sent by the port's server, one byte per segment, no handshake in the capture."""
    server, client = hc._ip(10), hc._ip(2)

    def frames():  # type: ignore[no-untyped-def]
        for i in range(len(data)):
            yield 1.7e9 + i * 1e-5, hc._frame(server, port, client, 40000, 5000 + i, hc.ACK, data[i : i + 1])

    return hc.write(path, frames())


def counted(monkeypatch: pytest.MonkeyPatch, owner: Any, name: str) -> list[int]:
    """Count the calls of `owner.name` (a method or a function) during a run."""
    calls = [0]
    original: Callable[..., Any] = getattr(owner, name)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        calls[0] += 1
        return original(*args, **kwargs)

    monkeypatch.setattr(owner, name, wrapper)
    return calls


def _offsets_searched(m: pytest.MonkeyPatch) -> list[int]:
    """The real-time port: offsets its size search looks at (every call used to start at 0)."""
    seen = [0]
    original = realtime.RealtimeConnection._size

    def size_of(self: realtime.RealtimeConnection, final: bool) -> int | None:
        seen[0] += max(0, len(self.search) - self.searched)
        return original(self, final)

    m.setattr(realtime.RealtimeConnection, "_size", size_of)
    return seen


COUNTERS: dict[int, Callable[[pytest.MonkeyPatch], list[int]]] = {
    30004: lambda m: counted(m, framing.Framing, "plausible"),  # RTDE: header candidates
    30001: lambda m: counted(m, framing.Framing, "plausible"),  # primary
    30003: _offsets_searched,  # real-time: size candidates
    50001: lambda m: counted(m, RecordCodec, "plausible"),  # URCL reverse: record offsets
    50003: lambda m: counted(m, RecordCodec, "plausible"),  # trajectory
    50004: lambda m: counted(m, RecordCodec, "plausible"),  # script command
}


def _run(tmp_path: Path, port: int, size: int) -> tuple[int, CaptureSummary]:
    path = one_byte_segments(tmp_path / f"{port}-{size}.pcap", port, garbage(size))
    with pytest.MonkeyPatch.context() as m:
        calls = COUNTERS[port](m)
        summary = decode_capture(path, ArrowSink())
    return calls[0], summary


@pytest.mark.parametrize("port", sorted(COUNTERS))
def test_a_byte_by_byte_stream_without_boundaries_costs_its_length(tmp_path: Path, port: int) -> None:
    small, _ = _run(tmp_path, port, 2000)
    big, _ = _run(tmp_path, port, 8000)
    assert big <= 4 * small * 1.5 + 1000, f"port {port}: 4x the bytes, {big / max(small, 1):.1f}x the work"
    assert big <= 40 * 8000, f"port {port}: {big} checks for 8,000 bytes"


@pytest.mark.parametrize("port", [30004, 30003])
def test_bytes_that_hold_no_package_are_reported(tmp_path: Path, port: int) -> None:
    """Past one package's length, bytes before the first boundary are damage, not a lead-in
    (RTDE: 64 kB; primary messages may be 1 MB, so its lead-in may be too)."""
    _, summary = _run(tmp_path, port, 80_000)
    assert summary.damage(), f"port {port}: 80 kB of no package said nothing"


def test_the_real_time_search_holds_a_bounded_window(tmp_path: Path) -> None:
    held: list[int] = []
    original = realtime.RealtimeConnection.feed

    def feed(self: realtime.RealtimeConnection, sender: str, chunk: Any) -> None:
        original(self, sender, chunk)
        # one byte per chunk here, so the chunks' count is their bytes: summing them on every
        # feed made this test quadratic (634 s for 150 kB; the decoder itself took seconds)
        held.append(len(self.search) + len(self.held))

    with pytest.MonkeyPatch.context() as m:
        m.setattr(realtime.RealtimeConnection, "feed", feed)
        path = one_byte_segments(tmp_path / "rt1.pcap", 30003, garbage(150_000))
        summary = decode_capture(path, ArrowSink())
    assert max(held) <= 2 * realtime.WINDOW + 16
    assert any("150000 bytes hold no real-time message" in p for p in summary.problems()), summary.problems()
