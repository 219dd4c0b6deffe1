"""Copying a batch's columns out of the packages into native, contiguous arrays, cache first.

What Parquet's writer does before encoding (`parquet.prepared_columns`), the costly part of
writing a capture's batch: numpy copies with the GIL released and no writer's state, so the
workers of `capture --jobs` run it beside the reading.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from rtde_spec.output.base import flat_columns

DEFAULT_BLOCK = 1 << 20  # bytes copied at a time where the cache's size is unknown


def block_rows(stride: int) -> int:
    """Rows of packages `stride` bytes apart copied at a time (`block_bytes()` of them, at least 64)."""
    return max(64, block_bytes() // max(1, stride))


@functools.cache
def block_bytes() -> int:
    """The packages' bytes copied at a time: this core's level-2 cache (`block_for`)."""
    return block_for(level2_cache())


def block_for(cache: int | None) -> int:
    """A block as large as a level-2 cache of `cache` bytes, within 512 kB - 2 MB.

    A block is read from memory once, then from the cache per run of fields, so it must
    stay in the cache while its runs are copied out: 2 MB blocks, as quick as 512-row ones
    on a core with 4 MB of it, took twice as long as 1 MB ones on a core with 1 MB (the copy
    of a 1 M-package capture, 0.52 against 0.27 s). Each block and run is one numpy copy with
    the GIL released: a worker preparing a batch takes the GIL back after each, so blocks are
    as large as the cache allows (512-row blocks made ~200 hand-overs a batch, 2 MB ones ~60).
    """
    return DEFAULT_BLOCK if cache is None else min(max(cache, 512 << 10), 2 << 20)


def level2_cache(cpu: Path = Path("/sys/devices/system/cpu/cpu0/cache")) -> int | None:
    """The first CPU's level-2 data cache in bytes (Linux sysfs: "1024K"); None where unknown."""
    try:
        for index in sorted(cpu.glob("index*")):
            level, kind = ((index / name).read_text().strip() for name in ("level", "type"))
            if level == "2" and kind != "Instruction":
                text = (index / "size").read_text().strip().upper()
                return int(text.rstrip("KM")) << {"K": 10, "M": 20}.get(text[-1:], 0)
    except (OSError, ValueError):
        return None
    return None


def native_columns(columns: Mapping[str, Any]) -> dict[str, Any]:
    """`flat_columns` (the same names, values and types), copied the way the cache likes.

    The columns of a batch are fields of the same packages, often a view of the capture
    file, one package per row. Copied column by column (`astype`), every package's
    cache lines are fetched once per column: 160 times for a 58-field recipe. Fields
    that follow each other in the package with one type (most of a recipe: vectors of
    doubles) are copied together here, a block of rows at a time, so each block is read
    from memory once: half the time, and a few dozen numpy calls instead of 160.
    """
    import numpy as np

    out: dict[str, Any] = {}
    runs: list[tuple[Any, list[Any]]] = []  # (the packages' bytes of one run of fields, its outputs)
    run: list[tuple[str, Any]] = []
    for name, column in [*columns.items(), ("", None)]:
        if run and (column is None or not _continues(run[-1][1], column)):
            runs.append(_run_columns(np, run, out))
            run = []
        if column is None:
            break
        if _in_packages(column):
            run.append((name, column))
        else:
            out.update(flat_columns({name: column}))  # a column of its own (text, bytes, native)
    size = len(next(iter(columns.values()))) if columns else 0
    step = block_rows(max((abs(source.strides[0]) for source, _ in runs), default=1))
    for start in range(0, size, step):
        for source, targets in runs:
            rows = source[start : start + step]
            for target in targets:
                target[:, start : start + step] = rows.T
    return out


def _in_packages(column: Any) -> bool:
    """A wire number (big-endian), a field of packages: one value or a vector per row."""
    if column.dtype.isnative or column.dtype.kind not in "fiu" or column.ndim not in (1, 2):
        return False
    return column.ndim == 1 or column.strides[1] == column.dtype.itemsize


def _continues(before: Any, column: Any) -> bool:
    """`column` starts where `before` ends, in the same rows, with the same type."""
    width = before.dtype.base.itemsize * (before.shape[1] if before.ndim == 2 else 1)
    return (
        column.dtype.base == before.dtype.base
        and len(column) == len(before)
        and column.strides[0] == before.strides[0]
        and (column.ndim == 1 or column.strides[1] == column.dtype.base.itemsize)
        and column.__array_interface__["data"][0] == before.__array_interface__["data"][0] + width
    )


def _run_columns(np: Any, run: list[tuple[str, Any]], out: dict[str, Any]) -> tuple[Any, list[Any]]:
    """One view of a run's bytes (rows x fields) and the native arrays it is copied into
    (one row of a 2-D array per output column, contiguous), named in `out`."""
    first = run[0][1]
    base = first.dtype.base
    widths = [(n, c.shape[1] if c.ndim == 2 else 0) for n, c in run]  # 0: one value, named as it is
    names = [f"{n}_{i}" if w else n for n, w in widths for i in range(max(w, 1))]
    source = np.lib.stride_tricks.as_strided(
        first, shape=(len(first), len(names)), strides=(first.strides[0], base.itemsize), writeable=False
    )
    target = np.empty((len(names), len(first)), dtype=base.newbyteorder("="))
    out.update(zip(names, target, strict=True))
    return source, [target]
