"""The CB3-era guide as text: tab-separated tables, rows one per line, blank lines between."""

from __future__ import annotations

from rtde_spec.importers.eseries_text import stops_in
from rtde_spec.importers.side_by_side import unfold
from rtde_spec.importers.tables import (
    FORM_FEED,
    PAGE_MARK,
    Table,
    check_rows,
    continues,
    is_heading,
    is_page_line,
    split_form_feeds,
)


def _is_furniture(cells: list[str]) -> bool:
    """A page's footer or header that came with a tab between its parts ("Copyright © … A/S.<TAB>Page
    1 of 9", "5/14/24, 10:15 AM<TAB>Real-Time Data Exchange (RTDE) Guide"): one or two cells, one a
    page mark. A field row has a name, a type and a comment, none of them a page mark."""
    parts = [c for c in cells if c]
    return 0 < len(parts) <= 2 and any(is_page_line(c) for c in parts)


def _repeats_header(last: Table, cells: list[str], gap: list[str]) -> bool:
    """Whether `cells` are `last`'s header again with no heading of a direction between: a page broke
    the table (its footer, the page number, the running title), whatever the footer's form."""
    if [c.lower() for c in cells] != [h.lower() for h in last.header]:
        return False
    return not any(is_heading(g) and Table(g.strip(), [], 0).direction for g in gap)


def _other_header(last: Table, cells: list[str]) -> bool:
    """Whether `cells` are another table's header (Data types: Name, Type, Size in bits): it starts
    that table whatever the page break before it, never rows "Name", "BOOL" of the field table."""
    low = [c.lower() for c in cells]
    return low[:1] == ["name"] and low != [h.lower() for h in last.header]


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
    # splitlines() dropped a page's form feed as a blank line; tables side by side go one after the other
    for number, raw in unfold(split_form_feeds(text)):
        line = raw.rstrip("\r\n")
        if not line.strip() and FORM_FEED not in line:
            continue
        cells = [c.strip() for c in line.split("\t")]
        if "\t" in line and _is_furniture(cells):
            line = "   ".join(c for c in cells if c)  # read as the footer line it is
        if "\t" not in line:
            if current is not None:
                last, gap, gap_at = current, [], number
            current = None
            gap.append(line)
            if is_heading(line) and not PAGE_MARK.match(line):
                heading = line.strip()
            continue
        if all(set(c) <= {"-"} for c in cells):  # the ruler that ends a table
            current = last = None
            continue
        if (
            current is None
            and last is not None
            and (continues(last, gap) or _repeats_header(last, cells, gap))
            and not _other_header(last, cells)
        ):
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
        elif [c.lower() for c in cells] == [h.lower() for h in current.header]:
            continue  # the header again inside the table (a page's top): never a field named "Name"
        else:
            current.rows.append((number, cells))
            count += 1
            check_rows(count, number)
    ends_in = current or last
    if ends_in is not None:
        stops_in(ends_in, gap, gap_at)
    return tables
