"""Decode capture files, one way down the stages: reading -> routing -> runs -> TCP -> framing ->
protocol decoders -> tables.

This module drives them: `reading/` gives segments (and bulk runs found with numpy),
`routing/` gives each its connection (by port, configurable, or by content) and frees
state that is done, `runs.py` batches whole data packages, `tcp.py` reassembles the
rest, `framing/` cuts packages, `protocols/` (one decoder per protocol behind
`ConnectionDecoder`) turns them into rows, and `tables/` writes them and sums up. None
of them calls back up. Every decoded package carries the capture time of the segment
that completed it. At the end every hole still open in a TCP stream is declared lost
and everything after it decoded.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT
from rtde_spec.capture.reading.packets import Segment, items
from rtde_spec.capture.routing.classify import fixed_record_ports, port_kinds
from rtde_spec.capture.routing.flows import SCRIPT_KIND, Flow, FlowTable, classify
from rtde_spec.capture.runs import Batcher
from rtde_spec.capture.tables.signals import signals_held
from rtde_spec.capture.tables.sink import (
    ArrowSink,
    DirectorySink,
    PreparedTables,
    TableSink,
    output_stem,
    series_stem,
)
from rtde_spec.capture.tables.summary import CaptureSummary
from rtde_spec.errors import OutputError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.versions import Version
from rtde_spec.recipes.codec import RecipeCodec

PLACE_ATTEMPTS = 8  # decodings of one file whose names other captures took meanwhile, before giving up


CapturePath = str | Path | Sequence[str | Path]  # a file, a pipe, or a split capture's parts in order


def first_part(path: CapturePath) -> str | Path:
    """The file a capture is named after: itself, or a split capture's first part."""
    return path if isinstance(path, (str, Path)) else path[0]


def label(path: CapturePath) -> str:
    """How messages name a capture: its path, or its first and last parts."""
    if isinstance(path, (str, Path)):
        return str(path)
    return str(path[0]) if len(path) == 1 else f"{path[0]} .. {path[-1]} ({len(path)} parts)"


def decode_capture(
    path: CapturePath,
    sink: TableSink,
    *,
    recipe: RecipeCodec | None = None,
    rtde_ports: Sequence[int] = (RTDE_PORT,),
    primary_ports: Sequence[int] = tuple(PRIMARY_PORTS.values()),
    catalogue: Catalogue | None = None,
    progress: Callable[[int], None] | None = None,
    port_map: Mapping[int, str] | None = None,
    controller: str | None = None,
) -> CaptureSummary:
    """Decode one capture file into the sink; the summary says what was found and what went wrong.

    `port_map` (port -> protocol, see classify.KINDS) adds to and overrides the spec's default ports.
    `controller` ("1.8", "3.3.1"): the version of a primary connection whose Version message is not
    in the capture (one started late); a Version message in the capture wins.
    A list of paths is the parts of one split capture (`reading/series.py`), decoded as one.
    """
    cat = catalogue or Catalogue.default()
    ports = port_kinds(rtde_ports, primary_ports, port_map)
    stats: dict[str, int] = {}
    session: dict[str, Any] = {}  # what this file's connections share (URCL programs: protocols/external.py)
    if controller is not None:
        session["controller"] = Version.parse(controller)
    table = FlowTable(lambda seg, mark: classify(seg, sink, recipe, ports, cat, session, mark))
    batcher = Batcher(table, _finish)
    try:
        for item in items(path, stats, progress, sink.lag, fixed=fixed_record_ports(ports)):
            if isinstance(item, Segment):
                batcher.segment(item)
            else:
                batcher.bulk(item)
    except BaseException as exc:  # Ctrl-C on a live pipe, a read error: what was decoded reaches the tables
        batcher.flush()
        for flow in table.live():
            flow.decoder.close()
        if isinstance(exc, KeyboardInterrupt):
            raise CaptureInterrupted(_summary(path, stats, table)) from exc
        raise
    batcher.flush()
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


def _summary(path: CapturePath, stats: dict[str, int], table: FlowTable) -> CaptureSummary:
    summary = CaptureSummary(label(path), stats.get("frames", 0), reading=dict(stats))
    summary.connections = table.summaries()
    return summary


class CaptureInterrupted(KeyboardInterrupt):
    """Ctrl-C (or SIGTERM) during a capture; `summary` says what was decoded before it.

    `kept`: whether that was written. A live pipe's tables are (Ctrl-C is how one ends);
    a file's are not: its tables of an earlier, finished run stay as they were, never
    replaced by the part read before the interrupt.
    """

    def __init__(self, summary: CaptureSummary, kept: bool = True) -> None:
        super().__init__()
        self.summary = summary
        self.kept = kept

    def __reduce__(self) -> tuple[Any, ...]:  # from a worker process (capture --jobs)
        return (type(self), (self.summary, self.kept))


def is_live(path: CapturePath) -> bool:
    """A pipe or standard input rather than a file: read once, as it comes, to its end."""
    try:
        return not Path(first_part(path)).is_file()
    except OSError:
        return True


def decode_to_directory(
    path: CapturePath,
    outdir: str | Path,
    fmt: str = "parquet",
    recipe_names: Sequence[str] | None = None,
    workers: int = 0,
    **kw: Any,
) -> CaptureSummary:
    """One file into OUTDIR (the unit of work of parallel and Dask runs; picklable arguments).

    `workers`: threads that prepare batches and write them in order while the capture is
    read on (`ordered_writes.OrderedWrites`; Parquet): the same files, on more cores.
    Its tables go in place under the names the folder gives their recipes (`tables/names.py`);
    when another capture placed a new recipe under one of them meanwhile, its files move to the
    names the folder gives now; MCAP files, which hold their table's name, are decoded again (a
    pipe cannot be: that is an error, nothing of it placed).
    """
    for _ in range(PLACE_ATTEMPTS):
        sink = directory_sink(path, outdir, fmt, workers)
        try:
            summary, prepared = decode_prepared(path, sink, recipe_names, **kw)
            if place(prepared, path, summary):
                return summary
        except BaseException:
            sink.abort()  # tables decoded but not placed (a stop came between) go too
            raise
        if is_live(path):
            raise OutputError(
                f"another capture gave a table name this one was written under to another recipe while "
                f"{label(path)} was read, and a pipe cannot be read again: nothing of it was put in place",
                subject=f"folder {outdir}",
            )
    raise OutputError(
        f"other captures kept taking the table names of {label(path)} ({PLACE_ATTEMPTS} times): "
        "nothing of it was put in place",
        subject=f"folder {outdir}",
    )


def directory_sink(
    path: CapturePath, outdir: str | Path, fmt: str = "parquet", workers: int = 0
) -> DirectorySink:
    """The sink of one capture's tables in OUTDIR, named after its file (`output_stem`), or the
    series of a split capture's parts (`series_stem`)."""
    stem = output_stem(path) if isinstance(path, (str, Path)) else series_stem(path)
    return DirectorySink(outdir, fmt, stem, workers=workers)


def decode_prepared(
    path: CapturePath, sink: DirectorySink, recipe_names: Sequence[str] | None = None, **kw: Any
) -> tuple[CaptureSummary, PreparedTables]:
    """One file decoded into `sink`, its tables finished beside their names but not yet in place
    (`place`): `capture --jobs N` decodes files in workers and places them in input order. After
    any error, `sink.abort()` drops whatever of it is not in place."""
    codec = RecipeCodec.for_names(recipe_names, "output") if recipe_names else None
    try:
        summary = decode_capture(path, sink, recipe=codec, **kw)
    except CaptureInterrupted as stop:
        if not is_live(path):  # unfinished: its earlier tables stay, nothing half is put in place
            with signals_held(replay=False):  # a second Ctrl-C must not cut the clean-up short
                sink.abort()
            stop.kept = False
            raise
        stop.summary.tables, stop.summary.paths = dict(sink.rows), [str(p) for p in sink.paths]
        if not place(_prepared(sink, path), path, stop.summary):  # a pipe's tables: what was decoded is kept
            stop.kept = False  # MCAP files named for a table another capture has taken since
            stop.summary.tables, stop.summary.paths = {}, []
        raise
    except OutputError as exc:  # a full disk: no table of this capture is kept half-written
        sink.abort()
        raise dropped_tables(exc, path) from exc
    except BaseException:
        if not is_live(path):  # a file can be read again: its earlier tables stay, nothing half is
            with signals_held(replay=False):  # put in place (a stop at its very end, in the workers of
                sink.abort()  # --jobs, put the tables it had in place and dropped the others)
            raise
        try:  # a pipe cannot: what was decoded before the error is kept, where its names are still right
            place(_prepared(sink, path), path)
        except OutputError:
            pass
        raise
    prepared = _prepared(sink, path)
    summary.tables = dict(sink.rows)
    summary.paths = [str(p) for p in sink.paths]
    return summary, prepared


def _prepared(sink: DirectorySink, path: CapturePath) -> PreparedTables:
    try:
        return sink.prepare()
    except OutputError as exc:
        sink.abort()
        raise dropped_tables(exc, path) from exc


def place(prepared: PreparedTables, path: CapturePath, summary: CaptureSummary | None = None) -> bool:
    """Put a decoded file's tables in place, under the names the folder gives their recipes now
    (`summary`'s tables and paths say where); False (nothing placed, nothing left) when those
    differ from the ones its MCAP files were written with: the file is to be decoded again."""
    try:
        placed = prepared.place()
    except OutputError as exc:
        prepared.discard()
        raise dropped_tables(exc, path) from exc
    except BaseException:
        prepared.discard()
        raise
    if not placed:
        prepared.discard()
    elif summary is not None:
        summary.tables = {prepared.renamed.get(t, t): n for t, n in summary.tables.items()}
        summary.paths = [str(p) for p in prepared.paths]
    return placed


def dropped_tables(exc: OutputError, path: CapturePath) -> OutputError:
    """A write error of one table, said for the whole capture: none of its tables was kept."""
    reason = exc.reason.split("; ")[0]
    kept = f"no table of {label(path)} was kept; files of earlier runs are as they were"
    return OutputError(f"{reason}; {kept}", errno=exc.errno, subject=exc.subject)


def capture_tables(path: CapturePath, recipe: Sequence[str] | None = None, **kw: Any) -> dict[str, Any]:
    """The tables of one capture as pyarrow Tables (`.to_pandas()` for DataFrames); a list of paths
    is the parts of one split capture, in order (`reading.series.group` orders them)."""
    codec = RecipeCodec.for_names(recipe, "output") if recipe else None
    sink = ArrowSink()
    decode_capture(path, sink, recipe=codec, **kw)
    return sink.tables()
