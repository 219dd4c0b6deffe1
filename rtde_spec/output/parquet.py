"""Parquet output, streamed as row groups, encoded on a second thread where a core is free."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import IO, Any

from rtde_spec.errors import OutputError, UsageError, require
from rtde_spec.output.base import Writer, flatten
from rtde_spec.output.native_columns import native_columns
from rtde_spec.output.partfile import Part, device_failed, in_its_folder, is_special, write_failed
from rtde_spec.output.tables import arrow_table, arrow_type, rows_table
from rtde_spec.printable import safe_text

_PARQUET_BATCH_ROWS = 16384
CHUNK_METADATA_BYTES = 860  # what pyarrow holds per column chunk written, until the file closes
WHERE = "Parquet output"


class ParquetWriter(Writer):
    """Parquet, streamed as row groups of about `ROW_GROUP_ROWS`; the schema is the first batch's.

    Dictionary encoding, compression and statistics only where they pay: integer and
    bool columns (modes, bits, registers), and statistics for the timestamp. Float
    columns of robot data rarely repeat and do not compress (snappy saves under 1 %
    on them); encoding and compressing them anyway costs most of the write time.
    Snappy and uncompressed are what every Parquet reader reads.
    """

    # ~20 MB of the 58-field recipe: per column chunk the writer pays a fixed cost, which at
    # 4,096 rows was half its time (2.3 against 1.3 µs a row); readers also prefer big groups
    ROW_GROUP_ROWS = 16384
    THREADED: bool | None = None  # encode row groups on a second thread; None: when a second core is ours

    NEEDS_PATH = True

    def __init__(self, stream: IO[bytes] | str) -> None:
        part = getattr(stream, "part", None)  # a PartStream: written through it (it can give back its fd)
        if isinstance(stream, (str, os.PathLike)) and not is_special(Path(stream)):
            part = Part(stream)  # written beside the name, renamed into place when closed
            stream = str(part.temp)
        super().__init__(stream)  # type: ignore[arg-type]  # a path: pyarrow opens the file itself
        self.part = part
        self._bytes = 0  # Arrow bytes of the rows so far, for splitting by size
        self._row_bytes: float | None = None
        self._pa = require("pyarrow", "parquet", "Parquet output")
        self._pq = require("pyarrow._parquet", "parquet", "Parquet output")
        self._writer: Any = None
        self._rows: list[dict[str, Any]] = []
        self._tables: list[Any] = []
        self._held = 0
        self._pool: Any = None
        self._pending: Any = None
        self.schema: Any = (
            None  # the file's columns; None: the first batch's (a table's next part: its last's)
        )
        self.declared: Any = None  # `declare`: the schema every file of the table has
        self.types: dict[str, str] = {}  # `hint`: the type of a column that may hold only nulls
        self._groups = 0  # row groups handed to pyarrow: its footer holds each one's column chunks
        self.threaded: bool | None = None  # this file's `THREADED` (False: it is written on a worker)

    def _open(self, schema: Any) -> None:
        pa = self._pa
        self.schema = schema
        discrete = [f.name for f in schema if not pa.types.is_floating(f.type)]
        stats = [*discrete, *(["timestamp"] if "timestamp" in schema.names else [])]
        compression = {f.name: "snappy" if f.name in discrete else "none" for f in schema}
        self._written(self._create, schema, discrete or False, stats or False, compression)

    def _create(self, schema: Any, dictionary: Any, stats: Any, compression: Any) -> None:
        options = {"use_dictionary": dictionary, "write_statistics": stats, "compression": compression}
        self._writer = in_its_folder(lambda: LeanParquetWriter(self.stream, schema, **options), self.part)

    def declare(self, columns: Mapping[str, str]) -> None:
        pa = self._pa

        def field(name: str, kind: str) -> Any:
            return pa.field(name, arrow_type(kind), nullable=kind.endswith("?"))

        self.declared = pa.schema([field(n, t) for n, t in columns.items()])

    def hint(self, types: Mapping[str, str]) -> None:
        self.types.update(types)

    def _add(self, table_: Any) -> None:
        if self._writer is None:
            schema = self.schema if self.schema is not None else self.declared
            self._open(schema if schema is not None else table_.schema)
        if table_.schema != self._writer.schema:
            table_ = self._conformed(table_)
        self._tables.append(table_)
        self._held += table_.num_rows
        if len(self._tables) >= 256:  # many small batches (short connections): each costs its own buffers
            self._tables = [self._pa.concat_tables(self._tables).combine_chunks()]
        if self._row_bytes is None and table_.num_rows:  # measured once: a buffer walk costs ~0.5 ms
            self._row_bytes = table_.get_total_buffer_size() / table_.num_rows
        self._bytes += int(table_.num_rows * (self._row_bytes or 0))
        if self._held >= self.ROW_GROUP_ROWS:
            self._write_held()

    def _conformed(self, table_: Any) -> Any:
        """A later batch in the file's schema (its first batch's, or the declared one: columns
        this batch's source does not send are null); a column the file has not, or a value
        missing where the file has none, is an error naming it, not a corrupt file or lost data."""
        schema = self._writer.schema
        present, names = set(table_.column_names), set(schema.names)
        missing = [n for n in schema.names if n not in present]
        if missing and self.declared is not None:  # declared: what this batch's source does not send
            pa = self._pa
            for name in missing:
                table_ = table_.append_column(name, pa.nulls(table_.num_rows, schema.field(name).type))
        elif missing:
            raise UsageError(f"a batch lacks the file's columns {missing[:5]}", subject=WHERE)
        extra = [n for n in table_.column_names if n not in names]
        if extra:  # select() would drop them: values lost with no word
            raise UsageError(f"a batch has columns the file has not: {extra[:5]}", subject=WHERE)
        try:
            table_ = table_.select(schema.names)
            fits = all(f.nullable or not c.null_count for f, c in zip(schema, table_.columns, strict=True))
            if fits and table_.schema.types == schema.types:  # nullability alone differs: no copy
                return self._pa.Table.from_arrays(table_.columns, schema=schema)
            return table_.cast(schema)
        except (ValueError, self._pa.ArrowInvalid) as exc:
            raise UsageError(f"a batch does not fit the file's columns: {exc}", subject=WHERE) from exc

    def _write_held(self, last: bool = False) -> None:
        """Hand the held rows to the writing thread; at most one row group is in flight.

        pyarrow encodes with the GIL released, so on two cores the next batch decodes
        while this one is written. Memory stays bounded: one group held, one writing.
        The `last` group is written here: nothing is left to overlap it with (and a
        small output never starts the thread, nor imports its pool).
        """
        if not self._tables:
            return
        group = self._pa.concat_tables(self._tables)
        self._tables, self._held = [], 0
        self._groups += 1
        self._wait()
        threaded = self.threaded if self.threaded is not None else self.THREADED
        if last or not (threaded if threaded is not None else usable_cores() > 1):
            self._written(self._writer.write_table, group, row_group_size=group.num_rows)
            return
        if self._pool is None:
            from concurrent.futures import ThreadPoolExecutor

            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="parquet")
        self._pending = self._pool.submit(
            self._written, self._writer.write_table, group, row_group_size=group.num_rows
        )

    def _written(self, write: Any, *args: Any, **kwargs: Any) -> None:
        """Run a write of pyarrow's; its error (a full disk) marks the file failed and names it."""
        part = self.part
        if part is not None and part.failed is not None:
            raise part.failed
        try:
            write(*args, **kwargs)
        except OutputError:  # our own file said it already (a PartStream under pyarrow)
            raise
        except OSError as exc:
            if part is None:  # a device written directly (-o /dev/full): a full disk is named
                raise device_failed(exc, Path(str(self.stream))) from exc
            part.failed = write_failed(exc, part.target)
            raise part.failed from exc

    def flush(self) -> None:
        """Wait for the row group in flight; held rows wait for a whole group (or close)."""
        self._wait()

    def _wait(self) -> None:
        if self._pending is not None:
            pending, self._pending = self._pending, None
            pending.result()  # re-raises a write error here, in the caller's thread

    def write(self, record: Mapping[str, Any]) -> None:
        self._rows.append(flatten(record))
        self.rows += 1
        if len(self._rows) >= _PARQUET_BATCH_ROWS:
            self._flush_rows()

    def _flush_rows(self) -> None:
        if self._rows:
            rows, self._rows = self._rows, []
            self._add(rows_table(rows, self.types))

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        self.write_prepared(prepared_columns(columns))

    def write_prepared(self, prepared: Any) -> None:
        """A batch `prepared_columns` made (on any thread), written in the caller's order."""
        self._flush_rows()
        self._add(prepared)
        self.rows += prepared.num_rows

    def held_metadata(self) -> int:
        """pyarrow keeps every row group's column chunk metadata until the file closes (~860 bytes
        each, measured with pyarrow 26): 9 MB per million packages of a 58-field recipe."""
        columns = len(self._writer.schema) if self._writer is not None else 0
        return self._groups * columns * CHUNK_METADATA_BYTES

    def size(self) -> int:
        """The Arrow size of the rows so far: about the file's, as float columns stay uncompressed."""
        return self._bytes

    def _finish(self) -> None:
        try:
            self._flush_rows()
            if self._writer is not None:
                self._write_held(last=True)
                self._wait()
                self._written(self._writer.close)
                self._writer = None  # pyarrow's writer keeps the footer it wrote: let it go
        finally:
            if self._pool is not None:
                self._pool.shutdown()
        if not isinstance(self.stream, str):
            super()._finish()

    def suspend(self) -> None:
        """Only a file written through a `PartStream` gives back its descriptor (pyarrow's own holds it)."""
        if not isinstance(self.stream, str):
            self._wait()  # the row group in flight is written through the file first
            super().suspend()


# what pyarrow.parquet.ParquetWriter gives pyarrow's own writer when not told otherwise (pyarrow 14
# to 26); the rest are that writer's defaults. tests/test_parquet_lean.py: the same bytes.
PYARROW_PARQUET_DEFAULTS: dict[str, Any] = {
    "version": "2.6",
    "use_deprecated_int96_timestamps": False,
    "writer_engine_version": "V2",
    "data_page_version": "1.0",
    "use_compliant_nested_type": True,
    "store_schema": True,
    "use_dictionary": True,
    "compression": "snappy",
    "write_statistics": True,
}


class LeanParquetWriter:
    """`pyarrow.parquet.ParquetWriter` for a local file or a Python file object, without
    importing `pyarrow.parquet`: that module loads pyarrow's filesystems (S3, GCS, HDFS,
    Azure, and with them `ssl`), ~30 ms of CPU before a one-package capture writes a byte.
    The writer below it (`pyarrow._parquet`) is the same, given the same settings.
    """

    def __init__(self, where: Any, schema: Any, **options: Any) -> None:
        from pyarrow import OSFile, _parquet

        self.schema = schema
        self._file = _os_file(OSFile, where) if isinstance(where, str) else None  # as pyarrow opens a path
        try:
            self._writer = _parquet.ParquetWriter(
                self._file if self._file is not None else where,
                schema,
                **{**PYARROW_PARQUET_DEFAULTS, **options},
            )
        except BaseException:
            if self._file is not None:
                self._file.close()
            raise

    def write_table(self, table: Any, row_group_size: int | None = None) -> None:
        if not table.schema.equals(self.schema, check_metadata=False):
            raise ValueError(f"a table of another schema than the file's: {table.schema} vs {self.schema}")
        self._writer.write_table(table, row_group_size=row_group_size)

    def close(self) -> None:
        try:
            self._writer.close()
        finally:
            if self._file is not None:
                self._file.close()


def _os_file(os_file: Any, path: str) -> Any:
    """pyarrow's own file at `path` (written without the GIL). A name that is not UTF-8 (bytes
    Python keeps as surrogates: r\\xff.parquet) pyarrow cannot encode, and Parquet output of such
    a name failed with a codec error: it is opened here and handed over by its descriptor."""
    try:
        path.encode("utf-8")
    except UnicodeEncodeError:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        try:
            if os.path.isdir("/proc/self/fd"):
                return os_file(f"/proc/self/fd/{fd}", "wb")
        finally:
            os.close(fd)
        raise UsageError(
            "pyarrow cannot open a file whose name is not UTF-8 on this system; give another name",
            subject=f"file {safe_text(path)}",
        ) from None
    return os_file(path, "wb")


def prepared_columns(columns: Mapping[str, Any]) -> Any:
    """A batch of numpy columns as the Arrow table `ParquetWriter.write_prepared` takes.

    The costly part of writing a batch before encoding (copying every column out of the
    packages into native order: numpy, the GIL released) and no state of any writer, so
    a capture with `--jobs` runs it on worker threads while the file stays in order.
    """
    return arrow_table(native_columns(columns))


def usable_cores() -> int:
    """Cores this process may run on (its affinity where the system says, else all)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def one_core_per_process() -> None:
    """Worker processes that each take a core (`capture --jobs`) write Parquet in the calling thread."""
    ParquetWriter.THREADED = False
