"""Decode capture files, one way through: packets -> TCP streams -> framing -> records -> sink.

This module drives the layers (`packets`, `tcp`, `framing` inside `connections`, `sink`);
none of them calls back up. Connections are recognised by port (configurable) and, on
other ports, by content (an RTDE version request from the client). Every decoded
package carries the capture time of the segment that completed it. At the end every
hole still open in a TCP stream is declared lost and everything after it decoded.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtde_spec._generated.constants import DATA_PACKAGE_TYPE, PRIMARY_PORTS, RTDE_PORT
from rtde_spec.capture.bulk import SIZE_AT, SIZE_BYTES, TYPE_AT
from rtde_spec.capture.classify import port_kinds
from rtde_spec.capture.flows import SCRIPT_KIND, Flow, FlowTable, Route, classify
from rtde_spec.capture.packets import FIN, RST, SYN, Segment, expand, items
from rtde_spec.capture.sink import ArrowSink, DirectorySink, TableSink, output_stem
from rtde_spec.capture.summary import CaptureSummary
from rtde_spec.capture.tcp import MOD, RECENT
from rtde_spec.errors import OutputError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec

RUN_HEAD = PAYLOAD_OFFSET  # size, type, recipe id: the bytes every data package of one run shares
RUN_MIN, RUN_MAX = 16, 4096  # shorter runs go segment by segment; longer ones are cut


def decode_capture(
    path: str | Path,
    sink: TableSink,
    *,
    recipe: RecipeCodec | None = None,
    rtde_ports: Sequence[int] = (RTDE_PORT,),
    primary_ports: Sequence[int] = tuple(PRIMARY_PORTS.values()),
    catalogue: Catalogue | None = None,
    progress: Callable[[int], None] | None = None,
    port_map: Mapping[int, str] | None = None,
) -> CaptureSummary:
    """Decode one capture file into the sink; the summary says what was found and what went wrong.

    `port_map` (port -> protocol, see classify.KINDS) adds to and overrides the spec's default ports.
    """
    cat = catalogue or Catalogue.default()
    ports = port_kinds(rtde_ports, primary_ports, port_map)
    stats: dict[str, int] = {}
    session: dict[str, Any] = {}  # what this file's connections share (capture/external.py: URCL programs)
    table = FlowTable(lambda seg: classify(seg, sink, recipe, ports, cat, session))
    run: _Run | None = None  # data segments, one whole package each, in order: decoded together

    def one(seg: Segment) -> None:
        nonlocal run
        route = table.route_of(seg)
        if route is None:
            return
        if run is not None:
            if run.takes(route, seg):
                return
            run.flush()
            run = None
        run = _Run.start(route, seg)
        if run is None:
            _feed(route, seg)
        if table.due(seg.time):
            table.sweep(seg.time, _finish)

    try:
        for item in items(path, stats, progress, sink.lag):
            if isinstance(item, Segment):
                one(item)
                continue
            first = next(expand(item))
            route = table.route_of(first)
            if run is not None:  # segments held first, so the direction is where this run starts
                run.flush()
                run = None
            whole = _Run.start(route, first) if route is not None else None
            if whole is None:
                for seg in expand(item):  # not a run this connection can take whole: segment by segment
                    one(seg)
                continue
            flow, sender, direction = whole.route
            flow.last = float(item.times[-1])
            direction.advance(item.rows.size, item.rows[-(RECENT // item.rows.shape[1] + 1) :].tobytes())
            flow.decoder.feed_run(sender, whole.codec, item.rows, item.times)
    except BaseException as exc:  # Ctrl-C on a live pipe, a read error: what was decoded reaches the tables
        if run is not None:
            run.flush()
        for flow in table.live():
            flow.decoder.close()
        if isinstance(exc, KeyboardInterrupt):
            raise CaptureInterrupted(_summary(path, stats, table)) from exc
        raise
    if run is not None:
        run.flush()
    for flow in sorted(table.live(), key=lambda f: f.kind != SCRIPT_KIND):  # programs whole before readers
        _finish(flow)
    return _summary(path, stats, table)


def _finish(flow: Flow) -> None:
    """The end of the capture: every hole still open is lost; what follows it is decoded."""
    decoder = flow.decoder
    for sender, direction in flow.directions.items():
        for chunk in direction.drain():
            decoder.feed(sender, chunk)
    decoder.finish()
    for sender, framing in decoder.framings().items():
        if framing.buf:
            decoder.counts.errors.append(
                f"the capture ends inside a {sender} package ({len(framing.buf)} bytes of it)"
            )
    decoder.close()


def _summary(path: str | Path, stats: dict[str, int], table: FlowTable) -> CaptureSummary:
    summary = CaptureSummary(str(path), stats.get("frames", 0), reading=dict(stats))
    summary.connections = table.summaries()
    return summary


class CaptureInterrupted(KeyboardInterrupt):
    """Ctrl-C during a capture (a live pipe); `summary` says what was decoded before it,
    and every table written is whole."""

    def __init__(self, summary: CaptureSummary) -> None:
        super().__init__()
        self.summary = summary


_NOT_DATA = SYN | FIN | RST


def _feed(route: Route, seg: Segment) -> None:
    flow, sender, direction = route
    for chunk in direction.feed(seg.time, seg.seq, seg.payload, syn=bool(seg.flags & SYN)):
        flow.decoder.feed(sender, chunk)


@dataclass
class _Run:
    """Consecutive segments of one direction, each exactly one data package of one recipe.

    At 500 Hz that is nearly every segment of an RTDE capture; they skip reassembly and
    framing one by one and are decoded in one `decode_many` (its prefix check still
    covers every package). A run too short to pay goes the per-segment way.
    """

    route: Route
    codec: RecipeCodec
    head: bytes  # size, type and recipe id every package of the run starts with
    next_seq: int
    segments: list[Segment]

    @classmethod
    def start(cls, route: Route, seg: Segment) -> _Run | None:
        flow, sender, direction = route
        payload = seg.payload
        if flow.kind != "rtde" or seg.flags & _NOT_DATA or len(payload) <= RUN_HEAD:
            return None
        size = int.from_bytes(payload[SIZE_AT : SIZE_AT + SIZE_BYTES], "big")
        if payload[TYPE_AT] != DATA_PACKAGE_TYPE or size != len(payload):
            return None
        if not direction.in_order_at(seg.seq):
            return None
        codec = flow.decoder.run_codec(sender, payload)
        if codec is None:
            return None
        return cls(route, codec, payload[:RUN_HEAD], (seg.seq + len(payload)) % MOD, [seg])

    def takes(self, route: Route, seg: Segment) -> bool:
        """Add the segment if it continues the run; False when it does not."""
        payload = seg.payload
        if (
            route is not self.route
            or seg.seq != self.next_seq
            or len(payload) != self.codec.package_size
            or seg.flags & _NOT_DATA
            or payload[:RUN_HEAD] != self.head
            or len(self.segments) >= RUN_MAX
        ):
            return False
        self.segments.append(seg)
        self.next_seq = (self.next_seq + len(payload)) % MOD
        return True

    def flush(self) -> None:
        if len(self.segments) < RUN_MIN:
            for seg in self.segments:
                _feed(self.route, seg)
            return
        flow, sender, direction = self.route
        import numpy as np

        data = b"".join(s.payload for s in self.segments)
        direction.advance(len(data), data[-RECENT:])
        rows = np.frombuffer(data, dtype=np.uint8).reshape(len(self.segments), -1)
        flow.decoder.feed_run(sender, self.codec, rows, np.array([s.time for s in self.segments]))


def decode_to_directory(
    path: str | Path,
    outdir: str | Path,
    fmt: str = "parquet",
    recipe_names: Sequence[str] | None = None,
    workers: int = 0,
    **kw: Any,
) -> CaptureSummary:
    """One file into OUTDIR (the unit of work of parallel and Dask runs; picklable arguments).

    `workers`: threads that prepare batches for the files while the capture is read on
    (`sink.OrderedWrites`; Parquet): the same files, on more cores.
    """
    codec = RecipeCodec.for_names(recipe_names, "output") if recipe_names else None
    sink = DirectorySink(outdir, fmt, output_stem(path), workers=workers)
    try:
        summary = decode_capture(path, sink, recipe=codec, **kw)
    except CaptureInterrupted as stop:
        sink.close()
        stop.summary.tables, stop.summary.paths = dict(sink.rows), [str(p) for p in sink.paths]
        raise
    except OutputError as exc:  # a full disk: no table of this capture is kept half-written
        sink.abort()
        raise dropped_tables(exc, path) from exc
    except BaseException:
        sink.close()
        raise
    try:
        sink.close()
    except OutputError as exc:
        sink.abort()
        raise dropped_tables(exc, path) from exc
    summary.tables = dict(sink.rows)
    summary.paths = [str(p) for p in sink.paths]
    return summary


def dropped_tables(exc: OutputError, path: str | Path) -> OutputError:
    """A write error of one table, said for the whole capture: none of its tables was kept."""
    reason = exc.reason.split("; ")[0]
    kept = f"no table of {path} was kept; files of earlier runs are as they were"
    return OutputError(f"{reason}; {kept}", errno=exc.errno, subject=exc.subject)


def capture_tables(path: str | Path, recipe: Sequence[str] | None = None, **kw: Any) -> dict[str, Any]:
    """The tables of one capture as pyarrow Tables (`.to_pandas()` for DataFrames)."""
    codec = RecipeCodec.for_names(recipe, "output") if recipe else None
    sink = ArrowSink()
    decode_capture(path, sink, recipe=codec, **kw)
    return sink.tables()
