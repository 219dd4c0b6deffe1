"""The CB3-era guide as text: tab-separated tables, rows one per line, blank lines between."""

from __future__ import annotations

from rtde_spec.importers.eseries_text import stops_in
from rtde_spec.importers.tables import (
    FORM_FEED,
    PAGE_MARK,
    Table,
    check_rows,
    continues,
    is_heading,
    split_form_feeds,
)


def read_tables(text: str, notes: list[str] | None = None) -> list[Table]:
    """The tables; one broken by a page ("Page 7 of 9", a running header, the header repeated)
    goes on as the same table (said in `notes`), its direction the heading's above its start."""
    tables: list[Table] = []
    heading = ""
    current: Table | None = None
    last: Table | None = None  # the table a page break may have cut
    gap: list[str] = []
    gap_at = 0  # the line the gap starts at
    count = 0
    for number, raw in split_form_feeds(text):  # splitlines() dropped a page's form feed as a blank line
        line = raw.rstrip("\r\n")
        if not line.strip() and FORM_FEED not in line:
            continue
        if "\t" not in line:
            if current is not None:
                last, gap, gap_at = current, [], number
            current = None
            gap.append(line)
            if is_heading(line) and not PAGE_MARK.match(line):
                heading = line.strip()
            continue
        cells = [c.strip() for c in line.split("\t")]
        if all(set(c) <= {"-"} for c in cells):  # the ruler that ends a table
            current = last = None
            continue
        if current is None and last is not None and continues(last, gap):
            current = last
            heading = last.heading
            if notes is not None:
                notes.append(f"line {number}: the table {last.heading!r} goes on after a page break")
            if [c.lower() for c in cells] == [h.lower() for h in last.header]:
                continue  # the header repeated at the top of the page
        last, gap = None, []
        if current is None:
            current = Table(heading, cells, number)
            tables.append(current)
        else:
            current.rows.append((number, cells))
            count += 1
            check_rows(count, number)
    ends_in = current or last
    if ends_in is not None:
        stops_in(ends_in, gap, gap_at)
    return tables
