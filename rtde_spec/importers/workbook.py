"""UR's client-interface workbook (.xlsx), read with openpyxl: every sheet, every table on it.

A table starts at a row whose first cells are a known header (Name, Type, Comment for RTDE
fields; Meaning, Type, Number of values for the real-time interface); a row of one short
text cell above it is its heading, and the sheet's title is the heading when there is none.
A real-time table's edition is its sheet's title ("RealTime_3.2", "3.0 and 3.1"). A sheet
holding the primary interface's C-like listing ("int packageSize", "for each joint: ...
end") is one edition of that interface, named by the sheet ("3.2"); the newest edition of
each product line is compared, the older sheets are reported. The workbook is opened
read-only (rows streamed), so a large file costs no more memory than its rows.
"""

from __future__ import annotations

import io
import re
import zipfile
from pathlib import Path
from typing import Any

from rtde_spec.errors import UsageError
from rtde_spec.importers.cells import Lines, full_version
from rtde_spec.importers.model import DocMember, Document
from rtde_spec.importers.primary_listing import SIGN, read_listing
from rtde_spec.importers.realtime_tables import edition_of_title, tables_in
from rtde_spec.importers.rows import is_placeholder
from rtde_spec.importers.sniff import ZIP, refuse_binary
from rtde_spec.importers.tables import MAX_BYTES, Table, check_rows
from rtde_spec.metamodel.schema import Spec
from rtde_spec.metamodel.versions import Version

_HEADERS = (("name", "type", "comment"), ("meaning", "type", "number of values"))
#: a field row's name cell: what may go on a table after blank rows
_ROW = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:\s*\(.*\))?$")


def _text(value: Any) -> str:
    return "" if value is None else " ".join(str(value).split())


def sheet_tables(title: str, rows: list[list[str]], count: int = 0) -> tuple[list[Table], int]:
    """The tables of one sheet's rows (cell texts), each under the heading above it."""
    tables: list[Table] = []
    heading = title
    current: Table | None = None
    gap = False  # blank rows since the table's last row
    for number, cells in enumerate(rows, start=1):
        while cells and not cells[-1]:
            cells = cells[:-1]
        if not cells:
            gap = current is not None
            continue
        if all(set(c) <= set("-") for c in cells):  # the ruler the CB3 guide ends a table with
            current, gap = None, False
            continue
        named = _ROW.match(cells[0]) or (current is not None and not current.is_field_table)
        if gap and not (named and len([c for c in cells if c]) >= 2):
            # text pasted from the CB3 guide has a blank row between some rows: a field's row after
            # them goes on the table; anything else ends it
            current = None
        gap = False
        head = tuple(c.lower() for c in cells if c)[:3]  # merged header cells read as empty ones
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
    from rtde_spec.importers import _type_enums, finish

    try:
        import openpyxl
    except ImportError:
        raise UsageError("reading .xlsx needs openpyxl: pip install 'rtde-spec[xlsx]'") from None
    if not path.is_file():
        raise UsageError(f"no such document: {path}")
    if path.stat().st_size > MAX_BYTES:
        raise UsageError(f"{path}: larger than {MAX_BYTES} bytes; not one of UR's workbooks")
    data = path.read_bytes()
    if not data.startswith(ZIP):
        refuse_binary(data, path)  # a PDF or an Excel 97-2003 .xls: said what to do
    try:
        # from its bytes: openpyxl refuses a workbook by its name (.xls, .xlsx.download) otherwise
        book = openpyxl.load_workbook(io.BytesIO(data), read_only=True, data_only=True)
    except (zipfile.BadZipFile, KeyError, ValueError, OSError) as exc:
        raise UsageError(f"{path}: not a readable .xlsx workbook ({type(exc).__name__}: {exc})") from None
    tables: list[Table] = []
    count = 0
    lines = Lines.of(spec)
    doc = Document(str(path), "xlsx", source or "client-interface-workbook")
    listings: list[tuple[str, str, list[DocMember]]] = []  # (version, sheet, members)
    try:
        for sheet in book.worksheets:
            raw = [["" if v is None else str(v) for v in row] for row in sheet.iter_rows(values_only=True)]
            rows = [[_text(v) for v in row] for row in raw]
            found, count = sheet_tables(sheet.title, rows, count)
            tables += found
            doc.realtime += tables_in(found, lines, sheet.title)
            # the listing's rows keep their indent: a "for each joint:" block ends where it does
            text = "\n".join(" ".join(c for c in r if c.strip()) for r in raw)
            if SIGN.search(text) or "int packageSize" in text:
                members = read_listing(text, _type_enums(spec))
                version, _ = edition_of_title(sheet.title, lines)
                if members:
                    listings.append((version or "", sheet.title, members))
    finally:
        book.close()
    _newest_listing(doc, listings, lines, line, edition)
    return finish(doc, tables, lines, line, edition or doc.edition, "e-series", spec=spec)


def _newest_listing(
    doc: Document,
    listings: list[tuple[str, str, list[DocMember]]],
    lines: Lines,
    line: str | None,
    edition: str | None,
) -> None:
    """The primary listing of the newest edition of the line (or --edition's sheet); others reported."""
    scoped = [(v, t, m) for v, t, m in listings if v and lines.line_of(v) is not None]
    if line is not None:
        scoped = [x for x in scoped if lines.line_of(x[0]) == line]
    if edition is not None:
        wanted = full_version(edition)
        scoped = [x for x in scoped if x[0] == wanted] or scoped
    if not scoped:
        for _v, title, _ in listings:
            doc.remarks.append(f"sheet {title!r}: a primary listing of no product line version, not compared")
        return
    newest = max(scoped, key=lambda x: Version.parse(x[0]))
    doc.members = newest[2]
    doc.line = lines.line_of(newest[0]) or ""
    doc.edition = newest[0]
    for _v, title, _ in listings:
        if title != newest[1]:
            doc.remarks.append(
                f"sheet {title!r}: the primary listing of an older edition, not compared "
                f"(sheet {newest[1]!r} is)"
            )
