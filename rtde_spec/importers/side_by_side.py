"""Two field tables side by side in a tab copy: unfolded into one after the other.

A page laid out in two columns (inputs beside outputs) copies as rows of both tables on one
line: `Name<TAB>Type<TAB>Comment<TAB>Version<TAB>Name<TAB>Type…`. Read as one table, the right
table's cells became the left rows' comments and versions (fields "changed", the right table's
"removed"). The header says it: its cells repeat. The right half of each line goes after the
left table, under the right half of the heading line ("Robot Controller Inputs<TAB>Robot
Controller Outputs", or two headings apart by spaces or on two lines, naming the two directions);
under one heading the halves are one table in two columns. Lines keep their numbers.
"""

from __future__ import annotations

import re

from rtde_spec.importers.tables import Table, is_heading

_HEADER_START = ("name", "type")
_APART = re.compile(r"\t+| {2,}")


def _halves(cells: list[str]) -> int | None:
    """Where the header's cells start again (the right table's first cell), else None."""
    low = [c.strip().lower() for c in cells]
    if tuple(low[:2]) != _HEADER_START:
        return None
    for at in range(2, len(low) - 1):
        if tuple(low[at : at + 2]) == _HEADER_START:
            return at
    return None


def unfold(lines: list[tuple[int, str]]) -> list[tuple[int, str]]:
    """The (number, line) pairs with each side-by-side block as two blocks, one after the other."""
    out: list[tuple[int, str]] = []
    i = 0
    while i < len(lines):
        number, line = lines[i]
        split = _halves(line.split("\t")) if "\t" in line else None
        if split is None:
            out.append((number, line))
            i += 1
            continue
        end = i + 1
        while end < len(lines) and "\t" in lines[end][1]:
            end += 1
        block = [(n, text.split("\t")) for n, text in lines[i:end]]
        right_heading = _right_heading(out)
        out += [(n, "\t".join(cells[:split])) for n, cells in block]
        if right_heading is not None:
            out.append(right_heading)
        out += [(n, "\t".join(cells[split:])) for n, cells in block if any(c.strip() for c in cells[split:])]
        i = end
    return out


def _right_heading(out: list[tuple[int, str]]) -> tuple[int, str] | None:
    """The right table's heading, taken off the lines before the header: the second half of a
    heading line holding both, or the second of two heading lines."""
    texts = [(k, n, t) for k, (n, t) in enumerate(out) if t.strip()]
    if not texts:
        return None
    k, number, last = texts[-1]
    parts = [p.strip() for p in _APART.split(last.strip()) if p.strip()]
    if len(parts) == 2 and {_direction(parts[0]), _direction(parts[1])} == {"input", "output"}:
        out[k] = (number, parts[0])
        return number, parts[1]
    before = texts[-2][2] if len(texts) >= 2 else "\t"
    if (
        "\t" not in before
        and is_heading(before)
        and {_direction(before), _direction(last)} == {"input", "output"}
    ):
        del out[k]  # the second of two headings, of the other direction: the right table's
        return number, last.strip()
    return None


def _direction(heading: str) -> str | None:
    return Table(heading.strip(), [], 0).direction


def unfold_tables(tables: list[Table], problems: list[str]) -> list[Table]:
    """Each table whose header cells repeat (HTML, Markdown: two tables laid side by side) as one
    table in two columns: the right half's rows after the left's, under the one heading the copy
    gives them. Said in `problems` (so --write holds): the halves may be inputs and outputs under
    a heading each, which the copy does not tell apart, and the left half's direction is a guess."""
    out: list[Table] = []
    for table in tables:
        split = _halves(table.header)
        if split is None or not table.is_field_table:
            out.append(table)
            continue
        whole = Table(table.heading, table.header[:split], table.line, cut=table.cut, open_end=table.open_end)
        whole.rows = [(n, cells[:split]) for n, cells in table.rows]
        whole.rows += [(n, cells[split:]) for n, cells in table.rows if any(c.strip() for c in cells[split:])]
        problems.append(
            f"the table at line {table.line} holds two tables side by side (its header cells repeat): "
            "read as "
            f"one table in two columns under {table.heading!r}; if its halves are inputs and outputs, "
            "copy each on its own"
        )
        out.append(whole)
    return out
