"""Streaming writers: one package (or one batch of data packages) in, bytes out, constant memory.

The decoder, the recorder and the capture decoder all write through these. Rows are
dicts keyed by the spec's field names; columnar batches are dicts of numpy columns.
CSV and Parquet flatten vectors to `name_0..name_N`, as UR's own recorder names them;
JSON keeps them as lists.
"""

from __future__ import annotations

import csv
import io
import json
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO, Any

from rtde_spec.errors import UsageError, require
from rtde_spec.output import jsonlines
from rtde_spec.output.background import BackgroundStream
from rtde_spec.output.tables import arrow_table
from rtde_spec.output.text import safe_text, table

FORMATS = ("table", "jsonl", "json", "csv", "parquet")
TABULAR = ("csv", "parquet")
_PARQUET_BATCH_ROWS = 16384
_JSON_SLICE_ROWS = 2048


def plain(value: Any) -> Any:
    """A JSON-able value: bytes as hex, tuples as lists, numpy scalars as Python numbers."""
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value).hex()
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if value is None or isinstance(value, (bool, str, float)):
        return value
    if isinstance(value, int):
        return int(value)
    if hasattr(value, "item"):
        return value.item()
    return str(value)


def flatten(record: Mapping[str, Any]) -> dict[str, Any]:
    """Vectors to name_0..name_N, bytes to hex, nested records to JSON text."""
    out: dict[str, Any] = {}
    for name, value in record.items():
        if isinstance(value, (list, tuple)) and all(isinstance(v, (int, float)) for v in value):
            for i, v in enumerate(value):
                out[f"{name}_{i}"] = v
        elif isinstance(value, (list, tuple, Mapping)):
            out[name] = json.dumps(plain(value))
        elif isinstance(value, (bytes, bytearray, memoryview)):
            out[name] = bytes(value).hex()
        else:
            out[name] = value
    return out


def _native(column: Any) -> Any:
    """The column in native byte order (big-endian wire values would convert one by one)."""
    return column if column.dtype.isnative else column.astype(column.dtype.newbyteorder("="))


def flat_columns(columns: Mapping[str, Any]) -> dict[str, Any]:
    """numpy columns (2-D for vectors) to 1-D columns named name_0..name_N, native byte order.

    Each output column is made contiguous and native in one pass, so Arrow takes it
    without another copy.
    """
    out: dict[str, Any] = {}
    for name, column in columns.items():
        native = column.dtype.newbyteorder("=")
        if column.ndim == 1:
            out[name] = column if column.dtype.isnative else column.astype(native)
        else:
            for i in range(column.shape[1]):
                out[f"{name}_{i}"] = column[:, i].astype(native)
    return out


def _dumps() -> Callable[[Any], bytes]:
    try:
        import orjson

        return orjson.dumps  # type: ignore[no-any-return]
    except ImportError:  # the standard library, slower but equal
        return lambda value: json.dumps(value, separators=(",", ":")).encode()


class Writer:
    """Base: counts rows; subclasses write them."""

    def __init__(self, stream: IO[bytes]) -> None:
        self.stream = stream
        self.rows = 0
        self.owns_stream = False  # open_writer's own file: closed with the writer

    def write(self, record: Mapping[str, Any]) -> None:
        raise NotImplementedError

    def flush(self) -> None:
        """Everything written so far is in the file (the recorder calls this per batch)."""
        self.stream.flush()

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        """A batch of data packages as numpy columns (same names as the rows would have)."""
        names = list(columns)
        lists = [columns[n].tolist() for n in names]
        for values in zip(*lists, strict=True):
            self.write(dict(zip(names, values, strict=True)))

    def close(self) -> None:
        stream = self.stream
        if isinstance(stream, BackgroundStream):
            stream.close()
            stream = stream.raw
        stream.flush()
        if self.owns_stream:
            stream.close()


class TableWriter(Writer):
    """One small field/value table per package, for reading in a terminal."""

    def write(self, record: Mapping[str, Any]) -> None:
        fields = dict(record)
        offset = fields.pop("offset", None)
        title = " ".join(safe_text(str(fields.pop(k))) for k in ("package", "package_type") if k in fields)
        head = f"@{offset}  {title}" if offset is not None else title
        rows = [[name, value] for name, value in fields.items()]
        text = head + "\n" + (table(["field", "value"], rows, max_width=100) + "\n" if rows else "") + "\n"
        self.stream.write(text.encode("utf-8", "backslashreplace"))
        self.rows += 1


class JsonLinesWriter(Writer):
    """One JSON object per line, written as it comes."""

    def __init__(self, stream: IO[bytes]) -> None:
        super().__init__(stream)
        self._dumps = _dumps()
        self._lines = jsonlines.formatter()

    def write(self, record: Mapping[str, Any]) -> None:
        self.stream.write(self._dumps(plain(record)) + b"\n")
        self.rows += 1

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        if jsonlines.fits(columns):
            rows = len(next(iter(columns.values())))
            for start in range(0, rows, _JSON_SLICE_ROWS):  # ~4 kB of text a row: bounded pieces
                piece = {n: c[start : start + _JSON_SLICE_ROWS] for n, c in columns.items()}
                self.stream.write(self._lines(piece))
            self.rows += rows
            return
        names = list(columns)
        lists = [_native(columns[n]).tolist() for n in names]  # C-speed conversion, native order first
        dumps = self._dumps
        lines = [dumps(dict(zip(names, values, strict=True))) for values in zip(*lists, strict=True)]
        if lines:
            self.stream.write(b"\n".join(lines) + b"\n")
        self.rows += len(lines)


class JsonWriter(JsonLinesWriter):
    """One JSON array, streamed: '[' first, ',' between, ']' at close.

    With `single`, an input of exactly one package prints as that object alone.
    """

    single = False

    def __init__(self, stream: IO[bytes]) -> None:
        super().__init__(stream)
        self._held: bytes | None = None

    def write(self, record: Mapping[str, Any]) -> None:
        text = self._dumps(plain(record))
        if self.rows == 0 and self.single:
            self._held = text
        else:
            if self._held is not None:
                self.stream.write(b"[\n" + self._held)
                self._held = None
            self.stream.write(b",\n" if self.rows else b"[\n")
            self.stream.write(text)
        self.rows += 1

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        Writer.write_columns(self, columns)

    def close(self) -> None:
        if self._held is not None:
            self.stream.write(self._held + b"\n")
        else:
            self.stream.write(b"\n]\n" if self.rows else b"[]\n")
        super().close()


class CsvWriter(Writer):
    """CSV with a header from the first row; columnar batches through pyarrow when installed."""

    def __init__(self, stream: IO[bytes]) -> None:
        super().__init__(stream)
        self._text = io.TextIOWrapper(stream, encoding="utf-8", newline="", write_through=True)
        self._csv = csv.writer(self._text)
        self._header: list[str] | None = None

    def _start(self, names: list[str]) -> None:
        if self._header is None:
            self._header = names
            self._csv.writerow(names)
        elif names != self._header:
            raise UsageError(
                "rows of different shapes cannot share one CSV table "
                f"(first: {len(self._header)} columns, now {len(names)}); use --format jsonl"
            )

    def write(self, record: Mapping[str, Any]) -> None:
        flat = flatten(record)
        self._start(list(flat))
        self._csv.writerow(flat.values())
        self.rows += 1

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        flat = flat_columns(columns)
        self._start(list(flat))
        try:
            import pyarrow.csv as pacsv
        except ImportError:
            lists = [c.tolist() for c in flat.values()]
            self._csv.writerows(zip(*lists, strict=True))
        else:
            options = pacsv.WriteOptions(include_header=False)
            pacsv.write_csv(arrow_table(flat), self.stream, write_options=options)
        self.rows += len(next(iter(flat.values()))) if flat else 0

    def close(self) -> None:
        self._text.detach()  # flushes the text layer and leaves the stream below to Writer.close
        super().close()


class ParquetWriter(Writer):
    """Parquet, streamed as row groups of about `ROW_GROUP_ROWS`; the schema is the first batch's.

    Dictionary encoding, compression and statistics only where they pay: integer and
    bool columns (modes, bits, registers), and statistics for the timestamp. Float
    columns of robot data rarely repeat and do not compress (snappy saves under 1 %
    on them); encoding and compressing them anyway costs most of the write time.
    Snappy and uncompressed are what every Parquet reader reads.
    """

    ROW_GROUP_ROWS = 4096
    THREADED = True  # encode row groups on a second thread; False where processes share the cores

    def __init__(self, stream: IO[bytes] | str) -> None:
        super().__init__(stream)  # type: ignore[arg-type]  # a path: pyarrow opens the file itself
        self._pa = require("pyarrow", "parquet", "Parquet output")
        self._pq = require("pyarrow.parquet", "parquet", "Parquet output")
        self._writer: Any = None
        self._rows: list[dict[str, Any]] = []
        self._tables: list[Any] = []
        self._held = 0
        self._pool: Any = None
        self._pending: Any = None

    def _open(self, schema: Any) -> None:
        pa = self._pa
        discrete = [f.name for f in schema if not pa.types.is_floating(f.type)]
        stats = [*discrete, *(["timestamp"] if "timestamp" in schema.names else [])]
        compression = {f.name: "snappy" if f.name in discrete else "none" for f in schema}
        self._writer = self._pq.ParquetWriter(
            self.stream,
            schema,
            use_dictionary=discrete or False,
            write_statistics=stats or False,
            compression=compression,
        )

    def _add(self, table_: Any) -> None:
        if self._writer is None:
            self._open(table_.schema)
        elif table_.schema != self._writer.schema:
            table_ = table_.select(self._writer.schema.names).cast(self._writer.schema)
        self._tables.append(table_)
        self._held += table_.num_rows
        if self._held >= self.ROW_GROUP_ROWS:
            self._write_held()

    def _write_held(self) -> None:
        """Hand the held rows to the writing thread; at most one row group is in flight.

        pyarrow encodes with the GIL released, so on two cores the next batch decodes
        while this one is written. Memory stays bounded: one group held, one writing.
        """
        if not self._tables:
            return
        group = self._pa.concat_tables(self._tables)
        self._tables, self._held = [], 0
        self._wait()
        if not self.THREADED:
            self._writer.write_table(group, row_group_size=group.num_rows)
            return
        if self._pool is None:
            from concurrent.futures import ThreadPoolExecutor

            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="parquet")
        self._pending = self._pool.submit(self._writer.write_table, group, row_group_size=group.num_rows)

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
            self._add(self._pa.Table.from_pylist(self._rows))
            self._rows = []

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        self._flush_rows()
        flat = flat_columns(columns)
        self._add(arrow_table(flat))
        self.rows += len(next(iter(flat.values()))) if flat else 0

    def close(self) -> None:
        self._flush_rows()
        try:
            if self._writer is not None:
                self._write_held()
                self._wait()
                self._writer.close()
        finally:
            if self._pool is not None:
                self._pool.shutdown()
        if not isinstance(self.stream, str):
            super().close()


_WRITERS: dict[str, type[Writer]] = {
    "table": TableWriter,
    "jsonl": JsonLinesWriter,
    "json": JsonWriter,
    "csv": CsvWriter,
    "parquet": ParquetWriter,
}


def format_for(path: str | None, fmt: str | None) -> str:
    """The format asked for, else the output file's suffix, else a table."""
    if fmt:
        return fmt
    suffix = Path(path).suffix.lower().lstrip(".") if path else ""
    return (
        {"pq": "parquet", "ndjson": "jsonl"}.get(suffix, suffix)
        if suffix in (*FORMATS, "pq", "ndjson")
        else "table"
    )


def open_writer(fmt: str, path: str | Path | None = None, *, background: bool = False) -> Writer:
    """A writer of `fmt` to a file (created) or to stdout.

    With `background`, a second thread does the file writes (for one long-running
    output such as `rtde-spec decode`; a dataset of many files keeps one thread).
    """
    if fmt not in _WRITERS:
        raise UsageError(f"unknown output format {fmt!r}", expected=", ".join(FORMATS))
    if fmt == "parquet" and path is None:
        raise UsageError("Parquet output needs a file: add -o FILE.parquet")
    if fmt == "parquet":
        return ParquetWriter(str(path))  # pyarrow's own file: written without the GIL
    stream: IO[bytes] = open(path, "wb") if path is not None else sys.stdout.buffer
    writer = _WRITERS[fmt](BackgroundStream(stream) if background else stream)  # type: ignore[arg-type]
    writer.owns_stream = path is not None
    return writer


def one_core_per_process() -> None:
    """Worker processes that each take a core (`capture --jobs`) write Parquet in the calling thread."""
    ParquetWriter.THREADED = False
