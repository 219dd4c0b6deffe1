"""A page break inside a table of the one-cell-per-line form: what is skipped, what is reported.

A printed page (a browser's print, a PDF turned to text) breaks a table with its furniture: the
page number or date line ("Page 7 of 9", "4/9", the page's address), a running header or footer
(the document's title, "RTDE Guide: inputs"), a heading "(continued)", the header cells again.
The table goes on after them with its direction unchanged (a running header naming the other
direction is no new section); a heading of the guide's own kind starts the next table. Any other
cell there (a cell pdftotext printed apart from its row, a row split over the page) is reported
with its line and not read, as no row can be said to be its.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from rtde_spec.importers.tables import Table, continues, is_heading, is_page_mark

_DIRECTION_WORD = re.compile(r"\b(?:in|out)puts?\b", re.I)
_HEADER_CELL = re.compile(r"name|type|comment|(?:introduced\s+in\s+)?version|introduced|since", re.I)


def is_furniture(text: str, running: frozenset[str]) -> bool:
    """A line a page puts around a table, not a cell of it."""
    return (
        is_page_mark(text)
        or text in running
        or bool(_HEADER_CELL.fullmatch(text.strip()))
        or "(continued)" in text.lower()
        or (is_heading(text) and bool(_DIRECTION_WORD.search(text)))
    )


def skip_page_break(
    paras: list[tuple[int, str]],
    at: int,
    table: Table,
    running: frozenset[str],
    starts_row: Callable[[str, str], bool],
    problems: list[str] | None,
    notes: list[str] | None,
) -> int | None:
    """Where the table goes on after the page mark at `at` (the next row's first cell), or None
    when it ends there: no row follows, or the page starts the next section."""
    end = at + 1
    while end + 1 < len(paras) and not starts_row(paras[end][1], paras[end + 1][1]):
        end += 1
    if end + 1 >= len(paras) or not continues(table, [p for _, p in paras[at:end]]):
        return None
    for number, text in paras[at + 1 : end]:
        if not is_furniture(text, running) and problems is not None:
            problems.append(
                f"line {number}: {text[:60]!r} after the page break at line {paras[at][0]} inside the "
                f"table {table.heading!r} is neither page furniture nor a row's cell (a cell printed "
                "apart from its row, or a row split over the page): not read"
            )
    if notes is not None:
        notes.append(f"line {paras[end][0]}: the table {table.heading!r} goes on after a page break")
    return end
