"""A text copy that stops inside a table: the user copied only part of the page.

An HTML page says so (its `<table>` is never closed); a text copy only stops. The readers mark a
table the text ends in (`Table.open_end`, and the row it stops in when too short to read, its
`stub`); here a table whose last row is not whole is taken as cut: that row is dropped (its
comment may stop mid-word), the table is marked cut (the spec's fields after it are not
reported as removed), and the problem names the table and the line the copy stops at, so
--check fails and --write refuses. A last row with every cell (its version cell filled, or
empty cells kept by tabs or `|`) is the table's own end, as far as the text can tell.
"""

from __future__ import annotations

from rtde_spec.importers.rows import is_placeholder, is_version_text
from rtde_spec.importers.tables import Table


def whole(table: Table, cells: list[str]) -> bool:
    """A row with a cell for every column of the header, or ending in its version cell."""
    return len(cells) >= len(table.header) or (len(cells) >= 3 and is_version_text(cells[-1]))


def mark_cut(tables: list[Table], problems: list[str]) -> None:
    """Mark the field tables a text copy stops inside, and say where (see the module's words)."""
    for table in tables:
        if not (table.open_end and table.is_field_table):
            continue
        stub = table.stub
        if stub is None and table.rows:
            line, cells = table.rows[-1]
            if is_placeholder(cells[0]) or whole(table, cells):
                continue  # "… and more": the copy says rows are left out; or a whole last row
            stub = (line, " ".join(c for c in cells if c)[:60])
            table.rows.pop()
        table.cut = True
        where = f"line {stub[0]} ({stub[1]!r}), a row not read" if stub else "its header"
        problems.append(
            f"the copy ends inside the table {table.heading or 'without a heading'!r} (line {table.line}, "
            f"{len(table.rows)} rows read; it stops at {where}): a copy cut short; the spec's fields "
            "after the cut are not reported as removed"
        )
