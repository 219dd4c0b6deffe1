"""What every writer shares: the Writer base, and records and numpy columns made flat
(vectors to `name_0..name_N`, as UR's own recorder names them; bytes as hex)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import IO, Any

from rtde_spec.errors import OutputError, UsageError
from rtde_spec.output.background import BackgroundStream
from rtde_spec.output.partfile import Part


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


def native_order(column: Any) -> Any:
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


class Writer:
    """Base: counts rows; subclasses write them.

    A writer of a file (`open_writer` with a path) writes it beside its name and
    renames it into place at `close` if rows were written (see `partfile`): a run
    that fails before its first row leaves an existing file as it was. As a context
    manager it is closed at the end of the block, or aborted if the block raised.
    """

    NEEDS_PATH = False  # True: given a file name, the writer opens the file itself (Parquet)
    closed = False  # close() or abort() was called

    def __init__(self, stream: IO[bytes]) -> None:
        self.stream = stream
        self.rows = 0
        self.owns_stream = False  # open_writer's own file: closed with the writer
        self.part: Part | None = None  # the file this writer makes appear, if it is one
        self.live = False  # a live file: in place from the first flushed row on

    def write(self, record: Mapping[str, Any]) -> None:
        raise NotImplementedError

    def hint(self, types: Mapping[str, str]) -> None:
        """The types (numpy codes, "str") of columns that may hold only nulls in a batch: a typed
        format gives them that type rather than none. Formats without column types ignore it."""

    def declare(self, columns: Mapping[str, str]) -> None:
        """Every column the file holds, in order, with its numpy type ("f8?": nullable), before
        the first row: a row or batch without one has it null. Formats without a fixed column
        set ignore it."""

    def flush(self) -> None:
        """Everything written so far is in the file (the recorder calls this per batch)."""
        self.stream.flush()
        if self.live and self.rows and self.part is not None:
            self.part.publish()

    def suspend(self) -> None:
        """Give back the file's descriptor until the next write (a dataset of many files)."""
        stream = self.stream
        if isinstance(stream, BackgroundStream):
            stream.flush()
            stream = stream.raw
        if hasattr(stream, "suspend"):
            stream.suspend()

    def held_metadata(self) -> int:
        """Bytes of the file's index this writer holds until it closes (Parquet's footer): a
        dataset starts the table's next part past a bound, so memory stays flat."""
        return 0

    def discard(self) -> None:
        """A prepared file is not put in place (another file of its dataset failed)."""
        self._settle(keep=False)

    def size(self) -> int:
        """Bytes written so far (an estimate where the format encodes later): for splitting."""
        return int(getattr(self.stream, "written", 0))

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        """A batch of data packages as numpy columns (same names as the rows would have)."""
        names = list(columns)
        lists = [columns[n].tolist() for n in names]
        for values in zip(*lists, strict=True):
            self.write(dict(zip(names, values, strict=True)))

    def close(self) -> None:
        """Finish the output; its file appears at its name if rows were written.

        After a failed write (a full disk) nothing of this run is committed: an existing
        file stays as it was, and the error names the file and what was kept. A second close
        does nothing.
        """
        if self._shut():
            return
        self.prepare()
        self.commit()

    def _shut(self) -> bool:
        """Whether it was closed before; from now on a write is a UsageError (rows written after
        close were lost without a word, or CSV's raised ValueError: buffer detached)."""
        was, self.closed = self.closed, True
        self.write = self.write_columns = self._write_after_close  # type: ignore[method-assign,assignment]
        return was

    def _write_after_close(self, *_: Any) -> None:
        raise UsageError("this writer is closed: what is written after close() would be lost")

    def prepare(self) -> None:
        """The first half of `close`: the file is finished beside its name, not yet in place.

        A dataset of many files prepares them all first, so a full disk while finishing
        the last one leaves none of them half in place.
        """
        part = self.part
        try:
            self._finish()
        except BaseException as exc:
            self._settle(keep=False)
            failure = self._failure(part)
            if failure is None:
                raise
            raise failure from exc
        failed: BaseException | None = self._failure(part) or getattr(self.stream, "failed", None)
        if failed is not None:  # a write failed earlier (in the background too): the file has a hole
            self._settle(keep=False)
            raise failed

    def commit(self) -> None:
        """The second half of `close`: a prepared file goes in place if rows were written."""
        self._settle(keep=self.rows > 0)

    @staticmethod
    def _failure(part: Part | None) -> OutputError | None:
        """The write error of `part`, with what it leaves at its name."""
        if part is None or part.failed is None:
            return None
        if part.published:
            kept = f"it keeps the first {part.kept} bytes, whole rows up to the last batch written"
        elif part.replaces:
            kept = "none of its rows were kept; the file that was there is as it was"
        else:
            kept = "none of its rows were kept"
        failed = part.failed
        return OutputError(f"{failed.reason}; {kept}", errno=failed.errno, subject=failed.subject)

    def __enter__(self) -> Writer:
        return self

    def __exit__(self, kind: type[BaseException] | None, *_: object) -> None:
        """`with open_writer(...) as w:` closes it, or aborts it on an error: a writer neither
        closed nor aborted left its temporary `.NAME.part-PID` file beside the name."""
        if kind is None:
            self.close()
        else:
            self.abort()

    def abort(self) -> None:
        """Close without keeping anything not already in place (an existing file stays)."""
        if self._shut():
            return
        try:
            self._finish()
        except Exception:  # the output is dropped anyway
            pass
        finally:
            self._settle(keep=False)

    def _finish(self) -> None:
        """Write what the format ends with and close the stream (subclasses add their end)."""
        stream = self.stream
        if isinstance(stream, BackgroundStream):
            stream.close()
            stream = stream.raw
        stream.flush()
        if self.owns_stream:
            stream.close()

    def _settle(self, keep: bool) -> None:
        part, self.part = self.part, None
        if part is None:
            return
        stream = self.stream
        if isinstance(stream, BackgroundStream):
            stream.close_quietly()
            stream = stream.raw
        if self.owns_stream and not stream.closed:
            try:
                stream.close()
            except OSError:
                pass
        if not keep:
            part.discard()
            return
        try:
            part.commit()
        except BaseException as exc:
            part.discard()
            failure = self._failure(part)  # no room for its name: a full disk, said with what stays
            if failure is None:
                raise
            raise failure from exc
