"""The CB3-era guide as text: tab-separated tables, rows one per line, blank lines between."""

from __future__ import annotations

from rtde_spec.importers.tables import Table, check_rows, is_heading


def read_tables(text: str) -> list[Table]:
    tables: list[Table] = []
    heading = ""
    current: Table | None = None
    count = 0
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.rstrip("\r\n")
        if not line.strip():
            continue
        if "\t" not in line:
            current = None
            if is_heading(line):
                heading = line.strip()
            continue
        cells = [c.strip() for c in line.split("\t")]
        if all(set(c) <= {"-"} for c in cells):  # the ruler that ends a table
            current = None
            continue
        if current is None:
            current = Table(heading, cells, number)
            tables.append(current)
        else:
            current.rows.append((number, cells))
            count += 1
            check_rows(count, number)
    return tables
