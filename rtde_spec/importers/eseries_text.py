"""The e-Series-era guide as text: each table cell on a line of its own, ended by `|`.

Rows are not always four lines: an empty comment and version come as `||` on one
line, a cell can be missing (safety_status), and the last row of a table can stop
short where the table ends (external_force_torque). A row therefore starts where
a name cell is followed by a type cell, not every fourth line.
"""

from __future__ import annotations

import re

from rtde_spec.importers.tables import PAGE_MARK, Table, check_rows, continues, is_heading
from rtde_spec.importers.wrapped import FRAGMENT

#: a paragraph standing for left-out rows
_ELLIPSIS = re.compile(r"^\s*(…|\.\.\.)|\band more\b", re.I)


def _cells(line: str) -> list[str] | None:
    """The cells of one line, or None when the line is not part of a table."""
    text = line.rstrip()
    if not text.endswith("|"):
        return None
    if text.strip() == "||":
        return ["", ""]
    return [text[:-1].strip()]


def read_tables(text: str, is_type: object = None, notes: list[str] | None = None) -> list[Table]:
    """Tables with their cells in document order; rows are split by `split_rows`.

    A page break inside a table ("Page 7 of 9", a running header, the header cells repeated)
    carries the table on: its direction stays the one of the heading above its start. Each
    carry-over is said in `notes`.
    """
    tables: list[Table] = []
    heading = ""
    cells: list[tuple[int, str]] = []
    header: list[str] = []
    start = 0
    in_table = False
    gap: list[str] | None = None  # lines since the table's last cell line
    resumed = -1  # where in `cells` the table went on after a page break (a header may repeat)

    def close() -> None:
        if header:
            table = Table(heading, list(header), start)
            table.rows = [(n, [c]) for n, c in cells]  # one cell per row until split_rows
            tables.append(table)

    for number, raw in enumerate(text.splitlines(), start=1):
        got = _cells(raw)
        if got is None:
            if in_table and gap is None:
                gap = []
            if gap is not None:
                gap.append(raw)
                continue
            if is_heading(raw):
                heading = raw.strip()
            continue
        if gap is not None:
            current = Table(heading, list(header), start)
            if header and continues(current, gap):
                resumed = len(cells)
                if notes is not None:
                    notes.append(f"line {number}: the table {heading!r} goes on after a page break")
            else:
                close()
                in_table, header, cells = False, [], []
                for line in gap:
                    if is_heading(line) and not PAGE_MARK.match(line):
                        heading = line.strip()
            gap = None
        if not in_table:
            in_table, start, header, cells, resumed = True, number, [], [], -1
        if raw.strip().startswith("|-") or raw.strip().startswith("|:"):
            if not header:
                header = [c for _, c in cells]
                cells = []
            elif resumed >= 0 and [c.lower() for _, c in cells[resumed:]] == [h.lower() for h in header]:
                del cells[resumed:]  # the header repeated at the top of the next page
            continue
        cells.extend((number, c) for c in got)
        check_rows(len(cells) // 4, number)
    if in_table:
        close()
        if tables and header:
            stops_in(tables[-1], gap or [], tables[-1].rows[-1][0] + 1 if tables[-1].rows else 0)
    return tables


def stops_in(table: Table, after: list[str], line: int) -> None:
    """Mark a table the text ends in: nothing after its last cell, or one line (from `line`; a cell
    cut before its end mark: a name is the row's stub, other text leaves the last row to be judged)."""
    rest = [line.strip() for line in after if line.strip()]
    if len(rest) > 1:
        return
    table.open_end = True
    if rest and FRAGMENT.fullmatch(rest[0]) and "_" in rest[0]:
        table.stub = (line + next(k for k, raw in enumerate(after) if raw.strip()), rest[0])


def split_rows(table: Table, starts_row: object) -> Table:
    """Group a table's cells into rows: a row starts at a name cell followed by a type cell."""
    assert callable(starts_row)
    flat = [(n, row[0]) for n, row in table.rows]
    out = Table(
        table.heading, table.header, table.line, cut=table.cut, open_end=table.open_end, stub=table.stub
    )
    i = 0
    while i < len(flat):
        if _ELLIPSIS.search(flat[i][1]) and len(flat[i][1]) <= 60:
            out.rows.append((flat[i][0], [flat[i][1]]))  # "… and more": a row of its own, reported
            i += 1
        elif i + 1 < len(flat) and starts_row(flat[i][1], flat[i + 1][1]):
            line, cells = flat[i][0], [flat[i][1], flat[i + 1][1]]
            i += 2
            while i < len(flat) and not (
                (i + 1 < len(flat) and starts_row(flat[i][1], flat[i + 1][1]))
                or (_ELLIPSIS.search(flat[i][1]) and len(flat[i][1]) <= 60)
            ):
                cells.append(flat[i][1])
                i += 1
            out.rows.append((line, cells))
        else:
            out.stray.append(flat[i])
            i += 1
    return out
