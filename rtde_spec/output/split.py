"""A long output as a series of closed part files, so a kill or power loss risks only the open one.

`-o run.parquet --split 60s` writes run_0000.parquet, run_0001.parquet, ... (as rosbag2
splits a bag): each part is closed, complete and renamed into place when it reaches
the limit, and the next one opens with the next batch. The parts read as one
dataset: `pyarrow.dataset.dataset(sorted(glob("run_*.parquet")))`, DuckDB
`read_parquet('run_*.parquet')`, Polars `scan_parquet("run_*.parquet")`; CSV and
JSON Lines parts likewise (`read_csv('run_*.csv')`).
"""

from __future__ import annotations

import contextlib
import re
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rtde_spec.errors import OutputError, UsageError
from rtde_spec.output.base import Writer

_UNITS = {
    "s": 1.0, "sec": 1.0, "min": 60.0, "m": 60.0, "h": 3600.0,
    "b": 1, "kb": 10**3, "mb": 10**6, "gb": 10**9, "kib": 2**10, "mib": 2**20, "gib": 2**30,
}  # fmt: skip
_TIME_UNITS = ("s", "sec", "min", "m", "h")
_LIMIT = re.compile(r"^\s*(\d+(?:\.\d*)?|\.\d+)\s*([a-zA-Z]+)\s*$")


@dataclass(frozen=True)
class SplitLimit:
    """When a part is full: after `seconds` since it opened, or at `size` bytes."""

    seconds: float | None = None
    size: int | None = None

    def __str__(self) -> str:
        return f"{self.seconds:g} s" if self.seconds is not None else f"{self.size} bytes"


def parse_split(text: str) -> SplitLimit:
    """'60s', '10min', '1h', '100MB', '2GiB' -> a SplitLimit (a bare number is an error: which unit?)."""
    match = _LIMIT.match(text)
    unit = match.group(2).lower() if match else ""
    if match is None or unit not in _UNITS:
        raise UsageError(
            f"--split {text!r}: a duration or a size with its unit",
            expected="e.g. 60s, 10min, 1h, 100MB, 2GiB",
        )
    value = float(match.group(1)) * _UNITS[unit]
    if unit in _TIME_UNITS:
        if value < 1:
            raise UsageError(f"--split {text!r}: parts of at least 1 s")
        return SplitLimit(seconds=value)
    if value < 4096:
        raise UsageError(f"--split {text!r}: parts of at least 4 kB")
    return SplitLimit(size=int(value))


def part_path(target: Path, index: int) -> Path:
    """run.parquet, 3 -> run_0003.parquet."""
    return target.with_name(f"{target.stem}_{index:04d}{target.suffix}")


def part_index(target: Path, path: Path) -> int | None:
    """The part number of `path` if it is a part of `target`, else None."""
    name, stem, suffix = path.name, target.stem, target.suffix
    if not (name.startswith(stem + "_") and name.endswith(suffix)):
        return None
    digits = name[len(stem) + 1 : len(name) - len(suffix)]
    return int(digits) if len(digits) >= 4 and digits.isdigit() else None


class SplitWriter(Writer):
    """Writes through one part writer at a time; a part is closed after the batch that fills it."""

    def __init__(self, open_part: Callable[[Path], Writer], target: Path, limit: SplitLimit) -> None:
        super().__init__(None)  # type: ignore[arg-type]  # the parts have the streams
        self._open_part = open_part
        self.target = target
        self.limit = limit
        self.index = 0
        self.paths: list[Path] = []  # parts in place so far
        self._current: Writer | None = None
        self._opened = 0.0

    def _writer(self) -> Writer:
        if self._current is None:
            path = part_path(self.target, self.index)
            self._current = self._open_part(path)
            if self.index == 0 and self._current.part is not None:
                self._current.part.placed = self._remove_stale
            self._opened = time.monotonic()
        return self._current

    def write(self, record: Mapping[str, Any]) -> None:
        with self._naming_parts():
            self._writer().write(record)
            self.rows += 1
            self._roll()

    def write_columns(self, columns: Mapping[str, Any]) -> None:
        with self._naming_parts():
            writer = self._writer()
            before = writer.rows
            writer.write_columns(columns)
            self.rows += writer.rows - before
            self._roll()

    def flush(self) -> None:
        if self._current is not None:
            with self._naming_parts():
                self._current.flush()

    @contextlib.contextmanager
    def _naming_parts(self) -> Iterator[None]:
        """A part that could not be written (a full disk) says which closed parts are complete."""
        try:
            yield
        except OutputError as exc:
            if not self.paths:
                raise
            first, last = self.paths[0].name, self.paths[-1].name
            kept = f"the {len(self.paths)} closed parts {first} .. {last} are complete"
            raise OutputError(f"{exc.reason}; {kept}", errno=exc.errno, subject=exc.subject) from exc

    def size(self) -> int:
        return self._current.size() if self._current is not None else 0

    def _roll(self) -> None:
        """Close the open part if it is full; the next write opens the next one."""
        writer = self._current
        if writer is None:
            return
        limit = self.limit
        full = (limit.seconds is not None and time.monotonic() - self._opened >= limit.seconds) or (
            limit.size is not None and writer.size() >= limit.size
        )
        if full:
            self._close_part()

    def _close_part(self) -> None:
        writer, self._current = self._current, None
        if writer is None:
            return
        kept = writer.rows > 0
        writer.close()
        if kept:
            self.paths.append(part_path(self.target, self.index))
            self.index += 1

    def _remove_stale(self) -> None:
        """Once this run's first part is in place, an earlier run's later parts are removed:
        a re-run replaces its own outputs, and a glob of the parts must not mix two runs."""
        folder = self.target.parent
        for path in folder.glob(f"{self.target.stem}_*{self.target.suffix}"):
            index = part_index(self.target, path)
            if index is not None and index > 0:
                path.unlink(missing_ok=True)

    def close(self) -> None:
        with self._naming_parts():
            self._close_part()

    def abort(self) -> None:
        writer, self._current = self._current, None
        if writer is not None:
            writer.abort()
