"""The sink, the last layer of a capture: a hive-partitioned directory of files, or Arrow tables.

Files are laid out as OUTDIR/<table>/robot=<controller address>/date=<YYYY-MM-DD>/<stem>.<ext>,
a dataset DuckDB, Polars and Spark read directly with hive partitioning (the address
percent-escaped as they unescape it: `robot=fd00%3A%3Ad3` for `fd00::d3`, `output/hive.py`). The stem names
the input and is unique to it (`output_stem`), so captures of the same name from different
folders never overwrite each other, and a re-run replaces its own outputs only. Every file
appears complete: the writers write beside the name and rename into place at close.
"""

from __future__ import annotations

import os
import stat
import time
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rtde_spec.capture.reading.compressed import SUFFIXES as COMPRESSED
from rtde_spec.capture.tables.names import Recipe, Register
from rtde_spec.capture.tables.ordered_writes import PREPARED, OrderedWrites
from rtde_spec.capture.tables.placing import EXTENSIONS, NamesTaken, PreparedTables, prune
from rtde_spec.errors import OutputError, require
from rtde_spec.output.base import Writer, flat_columns, flatten
from rtde_spec.output.hive import partition_folder
from rtde_spec.output.partfile import write_failed
from rtde_spec.output.writers import open_writer

UNKNOWN_DAY = "unknown"  # the partition of rows whose capture time is no date (a damaged record)


def day_of(capture_time: float) -> str:
    try:
        return time.strftime("%Y-%m-%d", time.gmtime(capture_time))
    except (OverflowError, OSError, ValueError):  # beyond the years a date holds, or NaN
        return UNKNOWN_DAY


def output_stem(path: str | Path) -> str:
    """The name of one input's outputs: its stem (`x` of x.pcapng.gz too) and 8 hex digits of its
    absolute path.

    Stable across re-runs of the same file (a re-run replaces its own outputs), and
    unique per input (a/x.pcap and b/x.pcap give x-<one>.parquet and x-<other>.parquet).
    A pipe (standard input) is a new capture each time: its stem gets the start time.
    """
    path = Path(path)
    try:
        regular = stat.S_ISREG(path.stat().st_mode)
    except OSError:
        regular = False
    if not regular:
        return f"{path.stem}-{time.strftime('%Y%m%dT%H%M%S', time.gmtime())}-{os.getpid()}"
    key = os.fsencode(os.path.realpath(path))
    name = path.with_suffix("") if path.suffix.lower() in COMPRESSED else path  # x.pcapng.gz: x
    return f"{name.stem}-{_sha1(key).hexdigest()[:8]}"


def series_stem(parts: Sequence[str | Path]) -> str:
    """The name of a split capture's outputs: its series' prefix (`part` of dumpcap's
    part_00001_....pcapng, `t` of tcpdump's t.pcap, t.pcap1, ...) and 8 hex digits of the
    series' folder and name pattern. The same for every run over the series, whichever parts
    it still holds: a re-run after a ring buffer dropped its oldest part replaces its outputs
    instead of writing the parts both runs read a second time under another name."""
    from rtde_spec.capture.reading.series import parts_of

    found = next((part for part in map(parts_of, parts) if part is not None), None)
    if found is None:  # no splitting tool's names: the first file names them
        return output_stem(parts[0])
    pattern = Path(found.series)
    name = pattern.name.split("*")[0].rstrip("_.-")
    name = Path(name).stem if "." in name else name  # tcpdump's t.pcap*: t
    key = os.fsencode(os.path.join(os.path.realpath(pattern.parent), pattern.name))
    return f"{name or 'capture'}-{_sha1(key).hexdigest()[:8]}"


def _sha1(data: bytes) -> Any:
    """SHA-1 from CPython's own module: `hashlib` loads OpenSSL first (~4 ms of every start)."""
    try:
        from _sha1 import sha1  # type: ignore[import-not-found]
    except ImportError:  # a Python built without it: OpenSSL's
        from hashlib import sha1
    return sha1(data)


class TableSink:
    """Rows and columnar batches by table name; `robot` and `day` pick the partition.

    `register`: the recipes the output folder's tables hold already (`names.Register`); a
    recipe's table is named by it, so one name never holds two recipes. None (in memory):
    numbered per capture in the order met."""

    def __init__(self, register: Register | None = None) -> None:
        self.rows: dict[str, int] = {}
        self.recipes: dict[Recipe, str] = {}  # (direction, names) -> table, in the order met
        self.register = register if register is not None else Register(Path("."))
        self.lag = 0  # blocks of a mapped input this sink may still read after it is given them
        self.declared: dict[str, dict[str, str]] = {}  # table -> every column it can have, numpy types
        self.hints: dict[str, dict[str, str]] = {}  # table -> column types for columns of nulls only

    def declare(self, table: str, columns: dict[str, str]) -> None:
        """The columns every file of `table` holds, in order, so files of different sources
        (controller versions) read as one table with one schema: name -> numpy type, ending in
        "?" where a source may not send it (null in that source's rows)."""
        self.declared[table] = columns

    def hint(self, table: str, types: Mapping[str, str]) -> None:
        """The types of `table`'s columns a batch may hold only nulls in (a field the controller's
        version does not send): typed, not of Arrow's null type, in every file."""
        self.hints.setdefault(table, {}).update(types)

    def table_for_recipe(self, direction: str, names: tuple[str, ...]) -> str:
        key = (direction, names)
        if key not in self.recipes:
            self.recipes[key] = self.register.table_for(key, self.recipes)
        return self.recipes[key]

    def row(self, table: str, robot: str, day: str, record: Mapping[str, Any]) -> None:
        self.rows[table] = self.rows.get(table, 0) + 1
        self._row(table, robot, day, record)

    def columns(self, table: str, robot: str, day: str, columns: Mapping[str, Any]) -> None:
        size = len(next(iter(columns.values())))
        self.rows[table] = self.rows.get(table, 0) + size
        self._columns(table, robot, day, columns)

    def _row(self, table: str, robot: str, day: str, record: Mapping[str, Any]) -> None:
        raise NotImplementedError

    def _columns(self, table: str, robot: str, day: str, columns: Mapping[str, Any]) -> None:
        raise NotImplementedError

    def close(self) -> None:
        pass


def descriptor_budget() -> int:
    """Files a dataset keeps open at once: an eighth of this process's descriptor limit, 8 to 64."""
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    except (ImportError, OSError, ValueError):
        return 32
    if soft == getattr(resource, "RLIM_INFINITY", -1) or soft <= 0:
        return 64
    return max(8, min(64, soft // 8))


PART_METADATA_BYTES = 16 << 20  # a table's file held in memory past this: its next part starts


class DirectorySink(TableSink):
    """One file per table, robot and day; at most `budget` of them hold a descriptor at once.

    A capture of hundreds of robots over many days has thousands of tables: the least
    recently written give back their descriptor (`Writer.suspend`) and reopen at their
    end when written again. Parquet files beyond the first `budget // 2` are written
    through our own file object, so they can be suspended too.

    A file whose writer holds more than `part_bytes` of index until it closes (Parquet's
    footer: ~9 MB per million packages of a 58-field recipe) is finished there, and the
    table goes on in STEM_0001.EXT, STEM_0002.EXT, ... beside it: memory stays flat
    however long the capture. The parts are put in place with the rest at close; parts of
    an earlier run of the same input that this run did not write are removed then.
    """

    def __init__(
        self,
        outdir: str | Path,
        fmt: str,
        stem: str,
        budget: int | None = None,
        workers: int = 0,
        part_bytes: int = PART_METADATA_BYTES,
    ) -> None:
        super().__init__(Register.read(outdir))
        self.outdir, self.fmt, self.stem = Path(outdir), fmt, stem
        self.writers: dict[tuple[str, str, str], Writer] = {}
        self.paths: list[Path] = []
        self.folders: set[Path] = set()  # partition folders this run made or used: removed when left empty
        self.part_bytes = part_bytes
        self.parts: dict[tuple[str, str, str], int] = {}  # parts finished before the open one
        self.schemas: dict[tuple[str, str, str], Any] = {}  # a table's columns, for its next part
        self.finished: list[Writer] = []  # parts finished beside their names, put in place at close
        self.budget = budget or descriptor_budget()
        self._pinned = self.budget // 2 if fmt == "parquet" else 0  # pyarrow's own files: fastest
        self._pinned_keys: set[tuple[str, str, str]] = set()
        self._open: OrderedDict[tuple[str, str, str], Writer] = OrderedDict()  # suspendable, by last use
        self.ahead = OrderedWrites(workers, self._write) if workers > 0 and fmt in PREPARED else None
        self.prepared: PreparedTables | None = None  # the tables finished by `prepare`, until placed
        if self.ahead is not None:  # batches are views of the file, prepared while it is read on
            self.lag = self.ahead.depth

    def _writer(self, table: str, robot: str, day: str) -> Writer:
        key = (table, robot, day)
        writer = self.writers.get(key)
        if writer is None:
            folder = self.outdir / table / partition_folder("robot", robot) / partition_folder("date", day)
            part = self.parts.get(key, 0)
            path = folder / f"{self.stem}{f'_{part:04d}' if part else ''}.{EXTENSIONS[self.fmt]}"
            pinned = len(self._pinned_keys) < self._pinned
            self.folders.add(folder)
            try:  # a folder or file that cannot be made (no inode left: a full disk) ends the run
                folder.mkdir(parents=True, exist_ok=True)
                writer = open_writer(self.fmt, path, suspendable=not pinned)
            except OutputError:
                raise
            except OSError as exc:
                raise write_failed(exc, path) from exc
            self.paths.append(path)
            if self.fmt == "mcap":  # one topic per table, as decode names them
                from rtde_spec.output.topics import topic_for_table

                writer.topic = topic_for_table(table)  # type: ignore[attr-defined]
            self.writers[key] = writer
            if self.ahead is not None:  # written on a worker already: row groups encoded in it
                writer.threaded = False  # type: ignore[attr-defined]
            if table in self.declared:
                writer.declare(self.declared[table])
            if table in self.hints:
                writer.hint(self.hints[table])
            if key in self.schemas:  # the table's next part: the columns of the parts before
                writer.schema = self.schemas[key]  # type: ignore[attr-defined]
            if pinned:
                self._pinned_keys.add(key)
        if key in self._pinned_keys:
            return writer
        self._open[key] = writer
        self._open.move_to_end(key)
        while len(self._open) > self.budget - len(self._pinned_keys):
            self._open.popitem(last=False)[1].suspend()
        return writer

    def hint(self, table: str, types: Mapping[str, str]) -> None:
        super().hint(table, types)
        for (name, _, _), writer in self.writers.items():
            if name == table:
                writer.hint(types)

    def _row(self, table: str, robot: str, day: str, record: Mapping[str, Any]) -> None:
        if self.ahead is not None:
            self.ahead.add((table, robot, day), None, record)
            return
        writer = self._writer(table, robot, day)
        writer.write(record)
        self._part_full((table, robot, day), writer)

    def _columns(self, table: str, robot: str, day: str, columns: Mapping[str, Any]) -> None:
        if self.ahead is not None:
            self.ahead.add((table, robot, day), PREPARED[self.fmt], columns)
            return
        writer = self._writer(table, robot, day)
        writer.write_columns(columns)
        self._part_full((table, robot, day), writer)

    def _write(self, key: tuple[str, str, str], prepared: bool, item: Any) -> None:
        """One item of `OrderedWrites`, in the order the decoder gave them (as without workers)."""
        writer = self._writer(*key)
        if prepared:
            writer.write_prepared(item)  # type: ignore[attr-defined]
        else:
            writer.write(item)
        self._part_full(key, writer)

    def _part_full(self, key: tuple[str, str, str], writer: Writer) -> None:
        """Finish the table's file here when its writer holds too much until close; the next
        write opens the next part."""
        if writer.held_metadata() <= self.part_bytes:
            return
        del self.writers[key]
        self._open.pop(key, None)
        self._pinned_keys.discard(key)
        self.parts[key] = self.parts.get(key, 0) + 1
        schema = getattr(writer, "schema", None)
        if schema is not None:
            self.schemas[key] = schema
        self.finished.append(writer)
        writer.prepare()  # its footer written and its memory given back; in place at close

    def abort(self) -> None:
        """Drop every table of this capture not in place yet (prepared ones too): files of earlier
        runs stay as they were."""
        if self.ahead is not None:
            self.ahead.drop()
        for writer in self.writers.values():
            writer.abort()
        for writer in self.finished:
            writer.discard()
        self.writers.clear()
        self.finished.clear()
        if self.prepared is not None:
            self.prepared.discard()
        for folder in self.folders:  # date=, robot= and table folders no file is left in
            prune(folder, folder.parent, folder.parent.parent)

    def close(self) -> None:
        """Every table finished first, then all put in place: a write error keeps none of them.

        Raises NamesTaken (nothing put in place) when the folder gave one of its recipes' names
        to another recipe while this capture was decoded: decode it again."""
        prepared = self.prepare()
        try:
            placed = prepared.place()
        except BaseException:
            prepared.discard()
            raise
        if not placed:
            prepared.discard()
            raise NamesTaken(f"{self.outdir}: a recipe's table name was taken while {self.stem} was decoded")

    def prepare(self) -> PreparedTables:
        """Every table finished beside its name, to be put in place by `PreparedTables.place`
        (in this process or another: the parent of `capture --jobs N` places files in input order)."""
        try:
            if self.ahead is not None:
                self.ahead.finish()
            for writer in self.writers.values():
                writer.prepare()
        except BaseException:
            self.abort()
            raise
        prepared = self.prepared = PreparedTables(
            self.outdir, self.stem, EXTENSIONS[self.fmt], [], list(self.paths), dict(self.recipes)
        )  # held here first: `abort` drops its files, however far this got
        for writer in [*self.finished, *self.writers.values()]:
            if writer.rows > 0 and writer.part is not None:
                prepared.parts.append(writer.part)
                writer.part = None  # its file is the PreparedTables' to place or drop now
            writer.commit()  # a writer without rows drops its temp file
        self.writers.clear()
        self.finished.clear()
        return prepared


class ArrowSink(TableSink):
    """Tables in memory, for the Python API (`capture_tables`)."""

    def __init__(self) -> None:
        super().__init__()
        self.pa = require("pyarrow", "arrow", "capture tables")
        self.pending: dict[str, list[dict[str, Any]]] = {}  # rows since the table's last batch
        self.parts: dict[str, list[Any]] = {}  # each table's batches, in the order given

    def _row(self, table: str, robot: str, day: str, record: Mapping[str, Any]) -> None:
        self.pending.setdefault(table, []).append({**flatten(record), "robot": robot, "date": day})

    def _columns(self, table: str, robot: str, day: str, columns: Mapping[str, Any]) -> None:
        self._rows_to_part(table)
        flat = flat_columns(columns)
        size = len(next(iter(flat.values())))
        batch = self.pa.table({**flat, "robot": [robot] * size, "date": [day] * size})
        self.parts.setdefault(table, []).append(batch)

    def _rows_to_part(self, table: str) -> None:
        rows = self.pending.pop(table, None)
        if rows:
            from rtde_spec.output.tables import rows_table

            self.parts.setdefault(table, []).append(rows_table(rows, self.hints.get(table)))

    def tables(self) -> dict[str, Any]:
        """One table each; batches of different columns (sources of several versions, rows beside
        batches) in one: a column one lacks is null there, a narrower integer widened."""
        for table in list(self.pending):
            self._rows_to_part(table)
        out = {}
        for name, parts in self.parts.items():
            out[name] = (
                parts[0] if len(parts) == 1 else self.pa.concat_tables(parts, promote_options="permissive")
            )
        return out
