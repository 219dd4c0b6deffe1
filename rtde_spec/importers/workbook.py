"""UR's client-interface workbook (.xlsx), read with openpyxl: every sheet, every table on it.

A table starts at a row whose first cells are a known header (Name, Type, Comment for RTDE
fields; Meaning, Type, Number of values for the real-time interface); a row of one short
text cell above it is its heading, and the sheet's title is the heading when there is none.
The workbook is opened read-only (rows streamed), so a large file costs no more memory
than its rows.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

from rtde_spec.errors import UsageError
from rtde_spec.importers.cells import Lines
from rtde_spec.importers.model import Document
from rtde_spec.importers.rows import is_placeholder
from rtde_spec.importers.tables import MAX_BYTES, Table, check_rows
from rtde_spec.metamodel.schema import Spec

_HEADERS = (("name", "type", "comment"), ("meaning", "type", "number of values"))


def _text(value: Any) -> str:
    return "" if value is None else " ".join(str(value).split())


def sheet_tables(title: str, rows: list[list[str]], count: int = 0) -> tuple[list[Table], int]:
    """The tables of one sheet's rows (cell texts), each under the heading above it."""
    tables: list[Table] = []
    heading = title
    current: Table | None = None
    for number, cells in enumerate(rows, start=1):
        while cells and not cells[-1]:
            cells = cells[:-1]
        if not cells:
            current = None
            continue
        head = tuple(c.lower() for c in cells[:3])
        if head in _HEADERS:
            current = Table(heading, cells, number)
            tables.append(current)
            continue
        if current is not None and is_placeholder(cells[0]):
            current.rows.append((number, cells))
            continue
        if len([c for c in cells if c]) == 1 and cells[0] and len(cells[0]) <= 60:
            heading = cells[0]
            if current is not None and not any(r for r in current.rows):
                current = None
            continue
        if current is not None:
            current.rows.append((number, cells))
            count += 1
            check_rows(count, number)
    return tables, count


def read_workbook(
    path: Path, spec: Spec, source: str | None, line: str | None, edition: str | None
) -> Document:
    """Every sheet's tables: RTDE field tables become fields; the report names each table."""
    from rtde_spec.importers import finish

    try:
        import openpyxl
    except ImportError:
        raise UsageError("reading .xlsx needs openpyxl: pip install 'rtde-spec[xlsx]'") from None
    if not path.is_file():
        raise UsageError(f"no such document: {path}")
    if path.stat().st_size > MAX_BYTES:
        raise UsageError(f"{path}: larger than {MAX_BYTES} bytes; not one of UR's workbooks")
    try:
        book = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except (zipfile.BadZipFile, KeyError, ValueError, OSError) as exc:
        raise UsageError(f"{path}: not a readable .xlsx workbook ({type(exc).__name__}: {exc})") from None
    tables: list[Table] = []
    count = 0
    try:
        for sheet in book.worksheets:
            rows = [[_text(v) for v in row] for row in sheet.iter_rows(values_only=True)]
            found, count = sheet_tables(sheet.title, rows, count)
            tables += found
    finally:
        book.close()
    doc = Document(str(path), "xlsx", source or "client-interface-workbook")
    return finish(doc, tables, Lines.of(spec), line, edition, "e-series")
