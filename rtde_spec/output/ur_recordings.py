"""Recordings made with UR's own RTDE client (its examples/record.py), read as tables.

People have them: record.py is what UR's RTDE guide points to. It writes a CSV whose cells
are separated by spaces (its CSVWriter's default), or with `--binary` a line of column names,
a line of their types (a vector's type once per component) and then each data package's
field bytes as the controller sent them (big-endian, without the package's header and recipe
id). `plot` reads both; the CSV's separator is found from its header line.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from rtde_spec.errors import DecodeError

SEPARATORS = (",", "\t", ";", " ")  # a comma wins where the header has one: names never hold one
_HEAD_LIMIT = 1 << 20  # bytes read for the two header lines: 1 MB is far past any recipe's


def separator(header: str) -> str:
    """The cell separator of a CSV, from its header line: the first of SEPARATORS in it."""
    return next((s for s in SEPARATORS if s in header.strip("\r\n")), ",")


def binary_layout(path: Path) -> tuple[list[str], list[str], int] | None:
    """(names, types, offset of the first row) when `path` is record.py's binary form, else None:
    its second line names only RTDE types, one per column."""
    with open(path, "rb") as f:
        return _binary_head(f.read(_HEAD_LIMIT))


def table_hint(head: bytes, source: str) -> str | None:
    """What a table file is, from its first bytes, and what reads it, when one is given where
    packages or a capture are expected (`decode`, `capture`)."""
    if head.startswith(b"\x89MCAP"):
        return "this is an MCAP file: open it in Foxglove or with the mcap tools"
    kind = recording_kind(head)
    if kind is None:
        return None
    return f"this is {kind}, a table already: `rtde-spec plot {source} FIELD -o plot.png` draws it"


def recording_kind(head: bytes) -> str | None:
    """What table `head` starts, of those `plot` reads; None when it is none of them."""
    if head.startswith(b"PAR1"):
        return "a Parquet table"
    if _binary_head(head) is not None:
        return "a binary recording of UR's record.py"
    try:
        first = head.split(b"\n", 1)[0].decode("ascii").strip()
    except UnicodeDecodeError:
        return None
    if not first.isprintable():  # packages' bytes (a setup names fields too, between binary)
        return None
    if first.startswith("{") and '"timestamp"' in first:
        return "a JSON Lines table"
    names = [re.sub(r"_\d+$", "", n) for n in first.split(separator(first)) if n]
    known = _field_names()
    if len(names) >= 2 and sum(n in known for n in names) * 2 >= len(names):
        return "a recorded table (CSV)"
    return None


def _field_names() -> set[str]:
    from rtde_spec.metamodel.catalogue import Catalogue

    catalogue = Catalogue.builtin()
    return {*catalogue.names("output"), *catalogue.names("input"), "capture_time"}


def _binary_head(head: bytes) -> tuple[list[str], list[str], int] | None:
    from rtde_spec.metamodel.catalogue import Catalogue

    first = head.find(b"\n")
    second = head.find(b"\n", first + 1) if first >= 0 else -1
    if second < 0:
        return None
    try:
        names = head[:first].decode("ascii").split()
        types = head[first + 1 : second].decode("ascii").split()
    except UnicodeDecodeError:
        return None
    wires = Catalogue.builtin().wire_types
    scalar = {n for n, w in wires.items() if w.count == 1 and w.size}
    if not names or len(names) != len(types) or not set(types) <= scalar:
        return None
    return names, types, second + 1


def read_binary(path: Path, problems: list[str]) -> dict[str, list[Any]]:
    """The columns of record.py's binary form; a last row cut short is said in `problems`."""
    import numpy as np

    from rtde_spec._generated.constants import BYTE_ORDER
    from rtde_spec.metamodel.catalogue import Catalogue

    layout = binary_layout(path)
    if layout is None:
        raise DecodeError("not a binary recording of UR's record.py", subject=f"file {path}")
    names, types, start = layout
    wires = Catalogue.builtin().wire_types
    dtype = np.dtype([(f"f{i}", BYTE_ORDER + wires[t].struct) for i, t in enumerate(types)])
    data = path.read_bytes()[start:]
    rows, rest = divmod(len(data), dtype.itemsize)
    if rest:
        problems.append(
            f"byte {start + rows * dtype.itemsize}: the last row is cut short "
            f"({rest} of {dtype.itemsize} bytes): dropped"
        )
    table = np.frombuffer(data, dtype=dtype, count=rows)
    return {name: table[f"f{i}"].tolist() for i, name in enumerate(names)}
