"""The guide as a browser renders it and people copy it: every table cell a paragraph of its own.

A table starts at the header cells `Name`, `Type`, `Comment` (and `Introduced in version`)
on lines of their own; its direction comes from the nearest heading above. Rows are found
as in the e-Series text form: where a name cell is followed by a type cell.
"""

from __future__ import annotations

import re

from rtde_spec.importers.tables import Table, check_rows, is_heading

_HEAD = ("name", "type", "comment")
_VERSION_HEAD = re.compile(r"(introduced in )?version|since", re.I)

#: the header cells as consecutive paragraphs (blank lines between allowed)
HEADER = re.compile(r"^[ \t]*Name[ \t]*\n(?:[ \t]*\n)*[ \t]*Type[ \t]*\n(?:[ \t]*\n)*[ \t]*Comment", re.M)


def read_tables(text: str) -> list[Table]:
    """Tables with one cell per row, for `eseries_text.split_rows` to group."""
    paras = [(n, raw.strip()) for n, raw in enumerate(text.splitlines(), start=1) if raw.strip()]
    tables: list[Table] = []
    current: Table | None = None
    heading = ""
    count = 0
    i = 0
    while i < len(paras):
        words = [p.lower() for _, p in paras[i : i + 3]]
        if tuple(words) == _HEAD:
            header = [p for _, p in paras[i : i + 3]]
            i += 3
            if i < len(paras) and _VERSION_HEAD.fullmatch(paras[i][1]):
                header.append(paras[i][1])
                i += 1
            if current is not None:  # the last lines before this header were its heading
                current.rows = [r for r in current.rows if r[1][0] != heading]
            current = Table(heading, header, paras[i - 1][0])
            tables.append(current)
            continue
        if current is not None and [p.lower() for p in words[:2]] == ["name", "type"]:
            # another table's header (Data types: Name, Type, Size in bits) ends the field table;
            # the short line before it is that table's title, not a cell of the last row
            if current.rows and i and current.rows[-1][0] == paras[i - 1][0] and is_heading(paras[i - 1][1]):
                current.rows.pop()
            current = None
        number, para = paras[i]
        if "input" in para.lower() or "output" in para.lower():
            if len(para) <= 60 and not para.endswith("."):
                heading = para
        if current is not None:
            current.rows.append((number, [para]))
            count += 1
            check_rows(count, number)
        i += 1
    return tables
