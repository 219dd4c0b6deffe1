"""Streaming writers: one package (or one batch of data packages) in, bytes out, constant memory.

The decoder, the recorder and the capture decoder all write through these. Rows are
dicts keyed by the spec's field names; columnar batches are dicts of numpy columns.
CSV and Parquet flatten vectors to `name_0..name_N`, as UR's own recorder names them;
JSON keeps them as lists.
"""

from __future__ import annotations

import io
import json
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from rtde_spec.errors import OutputError, UsageError
from rtde_spec.output.background import BackgroundStream
from rtde_spec.output.base import Writer, flat_columns, flatten, native_order, plain
from rtde_spec.output.parquet import ParquetWriter
from rtde_spec.output.partfile import DeviceStream, Part, PartStream, is_fifo, is_special
from rtde_spec.output.tables import arrow_table
from rtde_spec.output.text import safe_text, table

if TYPE_CHECKING:
    from rtde_spec.output.split import SplitLimit

FORMATS = ("table", "jsonl", "json", "csv", "parquet", "mcap")
TABULAR = ("csv", "parquet")
_JSON_SLICE_ROWS = 2048


def _dumps() -> Callable[[Any], bytes]:
    try:
        import orjson

        return orjson.dumps  # type: ignore[no-any-return]
    except ImportError:  # the standard library, slower but equal
        return lambda value: json.dumps(value, separators=(",", ":")).encode()


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
        from rtde_spec.output import jsonlines  # loaded with the first JSON Lines writer

        self._jsonlines = jsonlines
        self._lines = jsonlines.formatter()

    def write(self, record: Mapping[str, Any]) -> None:
        self.stream.write(self._dumps(plain(record)) + b"\n")
        self.rows += 1

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        if self._jsonlines.fits(columns):
            rows = len(next(iter(columns.values())))
            for start in range(0, rows, _JSON_SLICE_ROWS):  # ~4 kB of text a row: bounded pieces
                piece = {n: c[start : start + _JSON_SLICE_ROWS] for n, c in columns.items()}
                self.stream.write(self._lines(piece))
            self.rows += rows
            return
        names = list(columns)
        lists = [native_order(columns[n]).tolist() for n in names]  # C-speed conversion, native order first
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

    def _finish(self) -> None:
        if self._held is not None:
            self.stream.write(self._held + b"\n")
        else:
            self.stream.write(b"\n]\n" if self.rows else b"[]\n")
        super()._finish()


class CsvWriter(Writer):
    """CSV with a header from the first row; columnar batches through pyarrow when installed."""

    def __init__(self, stream: IO[bytes]) -> None:
        super().__init__(stream)
        self._text = io.TextIOWrapper(stream, encoding="utf-8", newline="", write_through=True)
        import csv  # loaded with the first CSV writer

        self._csv = csv.writer(self._text, lineterminator="\n")  # as pyarrow ends its rows: one ending
        self._header: list[str] | None = None
        self._declared: list[str] | None = None  # `declare`: the header of every file of the table

    def declare(self, columns: Mapping[str, str]) -> None:
        self._declared = list(columns)

    def _start(self, names: list[str]) -> bool:
        """The header written with the first row; whether these columns need padding to it."""
        if self._header is None:
            self._header = self._declared or names
            self._csv.writerow(self._header)
        if names == self._header:
            return False
        if self._declared and set(names) <= set(self._declared):
            return True
        raise UsageError(
            "rows of different shapes cannot share one CSV table "
            f"(first: {len(self._header)} columns, now {len(names)}); use --format jsonl"
        )

    def write(self, record: Mapping[str, Any]) -> None:
        flat = flatten(record)
        if self._start(list(flat)):
            flat = {name: flat.get(name) for name in self._header or ()}
        self._csv.writerow(flat.values())
        self.rows += 1

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        flat = flat_columns(columns)
        if self._start(list(flat)):  # what this source does not send: empty cells
            import numpy as np

            size = len(next(iter(flat.values())))
            flat = {
                n: flat[n] if n in flat else np.full(size, None, dtype=object) for n in self._header or ()
            }
        try:
            import pyarrow.csv as pacsv
        except ImportError:
            lists = [c.tolist() for c in flat.values()]
            self._csv.writerows(zip(*lists, strict=True))
        else:
            options = pacsv.WriteOptions(include_header=False)
            pacsv.write_csv(arrow_table(flat), self.stream, write_options=options)
        self.rows += len(next(iter(flat.values()))) if flat else 0

    def _finish(self) -> None:
        self._text.detach()  # flushes the text layer and leaves the stream below to Writer._finish
        super()._finish()


_WRITERS: dict[str, type[Writer] | str] = {  # a module's name: imported when that format is asked for
    "table": TableWriter,
    "jsonl": JsonLinesWriter,
    "json": JsonWriter,
    "csv": CsvWriter,
    "parquet": ParquetWriter,
    "mcap": "rtde_spec.output.mcap",
}
# Formats a reader reads while they grow (one complete line per row; MCAP's chunks, each batch
# closing one, read in order without the summary): a recording's file can be in place from its
# first batch on. A format with a footer it cannot be read without (Parquet) waits for close.
GROWING = {"jsonl", "csv", "mcap"}


def format_for(path: str | None, fmt: str | None) -> str:
    """The format asked for, else the output file's suffix, else a table."""
    if fmt:
        return fmt
    suffix = Path(path).suffix.lower().lstrip(".") if path else ""
    return (
        {"pq": "parquet", "ndjson": "jsonl"}.get(suffix, suffix)
        if suffix in (*_WRITERS, "pq", "ndjson")
        else "table"
    )


def _writer_class(fmt: str) -> type[Writer]:
    """The writer of `fmt`; one in a module of its own (MCAP) is imported only when used."""
    cls = _WRITERS[fmt]
    if isinstance(cls, str):
        import importlib

        cls = _WRITERS[fmt] = importlib.import_module(cls).McapWriter
    return cls


def open_writer(
    fmt: str,
    path: str | Path | None = None,
    *,
    background: bool = False,
    live: bool = False,
    durable: bool = False,
    split: SplitLimit | None = None,
    suspendable: bool = False,
) -> Writer:
    """A writer of `fmt` to a file or to stdout.

    A file is written beside its name and renamed into place at close if rows were
    written; a failed run leaves an existing file as it was (see `partfile`).
    With `live`, a growing format (CSV, JSON Lines) is in place from its first flushed
    row on, so a killed process leaves every flushed batch. With `durable`, files are
    synced before the rename. With `split`, the output is a series of part files
    NAME_0000.EXT, NAME_0001.EXT..., each closed (and complete) when it reaches the limit.
    With `background`, a second thread does the file writes (for one long-running
    output such as `rtde-spec decode`; a dataset of many files keeps one thread).
    With `suspendable`, every format writes through our own file, so `Writer.suspend`
    can give back its descriptor (Parquet too, instead of pyarrow opening the path).
    """
    if fmt not in _WRITERS:
        raise UsageError(f"unknown output format {fmt!r}", expected=", ".join(_WRITERS))
    cls = _writer_class(fmt)
    if path is None:
        if cls.NEEDS_PATH:
            raise UsageError(f"{fmt} output needs a file: add -o FILE.{fmt}")
        if getattr(sys.stdout, "closed_stream", False) or sys.stdout is None:
            raise UsageError("standard output is closed (>&-): what it would hold is lost; add -o FILE")
        out: IO[bytes] = BackgroundStream(sys.stdout.buffer) if background else sys.stdout.buffer  # type: ignore[assignment]
        return cls(out)
    if split is not None:
        from rtde_spec.output.split import SplitWriter

        def one_part(target: Path) -> Writer:
            return open_writer(fmt, target, background=background, live=live, durable=durable)

        return SplitWriter(one_part, Path(path), split)
    target = Path(path)
    if cls.NEEDS_PATH and is_fifo(target):  # pyarrow seeks its file: "lseek failed"
        raise UsageError(
            f"{fmt} cannot be written to a pipe (the file is written by a writer that seeks in it); "
            "give a file, or a format that streams: --format csv or jsonl",
            subject=f"-o {target}",
        )
    if cls.NEEDS_PATH and not (suspendable and not is_special(target)):
        writer = cls(str(target))  # type: ignore[arg-type]  # pyarrow's own file (written without the GIL) beside the target
        if writer.part is not None:
            writer.part.durable = durable
        return writer
    if is_special(target):  # -o /dev/null or a pipe: nothing to replace
        writer = cls(DeviceStream(target))  # type: ignore[arg-type]  # closed by the writer
        writer.owns_stream = True
        return writer
    part = Part(target, durable=durable)
    try:  # the background thread gathers blocks itself; pyarrow writes whole pages
        stream = PartStream(part, batched=not (background or cls.NEEDS_PATH))
    except OutputError as exc:  # not even the file could be made (a full disk): say what stays
        raise (Writer._failure(part) or exc) from exc
    try:
        writer = cls(BackgroundStream(stream) if background else stream)  # type: ignore[arg-type]
    except BaseException:
        stream.close()
        part.discard()
        raise
    writer.owns_stream = True
    writer.part = part
    writer.live = live and fmt in GROWING
    return writer
