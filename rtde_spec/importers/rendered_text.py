"""The guide as a browser renders it and people copy it: every table cell a paragraph of its own.

A table starts at the header cells `Name`, `Type`, `Comment` (and `Introduced in version`)
on lines of their own; its direction comes from the nearest heading above. Rows are found
as in the e-Series text form: where a name cell is followed by a type cell. The same form
comes from a print to text and from pdftotext without -layout (`pdf_plain` makes its
paragraphs cells): a name the narrow column wrapped is rejoined (`wrapped`), a page break
inside a table is skipped (`page_break`), and the table ends after its last row's comment
and version, so the text after it is no part of that row.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Collection

from rtde_spec.importers import pdf_plain
from rtde_spec.importers.page_break import skip_page_break
from rtde_spec.importers.rows import is_placeholder, is_version_text
from rtde_spec.importers.tables import (
    FORM_FEED,
    Table,
    check_rows,
    is_heading,
    is_page_line,
    running_lines,
    split_form_feeds,
)
from rtde_spec.importers.wrapped import FRAGMENT, HYPHENATED, joins

_HEAD = ("name", "type", "comment")
_VERSION_HEAD = re.compile(r"(introduced in )?version|since", re.I)

#: the header cells as consecutive paragraphs (blank lines between allowed)
HEADER = re.compile(r"^[ \t]*Name[ \t]*\n(?:[ \t]*\n)*[ \t]*Type[ \t]*\n(?:[ \t]*\n)*[ \t]*Comment", re.M)

StartsRow = Callable[[str, str], bool]


def read_tables(
    text: str,
    starts_row: StartsRow | None = None,
    known: Collection[str] = (),
    problems: list[str] | None = None,
    notes: list[str] | None = None,
) -> list[Table]:
    """Tables with one cell per row, for `eseries_text.split_rows` to group; `starts_row(name, type)`
    tells a row's first two cells, `known` the spec's names (for names wrapped inside a word)."""
    starts = starts_row or (lambda _name, _type: False)

    def is_type(cell: str) -> bool:
        return starts("x", cell)

    if pdf_plain.is_pdftotext(text):
        paras = pdf_plain.cells(text, known, is_type, problems)
    else:
        paras = _lines(text, known, is_type, problems)
    tables = _tables(paras, starts, problems, notes)
    for table in tables:
        _end(table, starts)
    return tables


def _lines(
    text: str, known: Collection[str], is_type: Callable[[str], bool], problems: list[str] | None
) -> list[tuple[int, str]]:
    """The non-blank lines, a name wrapped over lines before its type cell rejoined (see `wrapped`:
    here a break inside a word is taken only where a part holds a `_`)."""
    paras = [(n, raw if raw == FORM_FEED else raw.strip()) for n, raw in split_form_feeds(text)]
    paras = [(n, p) for n, p in paras if p]
    out: list[tuple[int, str]] = []
    for i, (number, para) in enumerate(paras):
        if out and i + 1 < len(paras) and is_type(paras[i + 1][1]) and FRAGMENT.fullmatch(para):
            first = len(out)
            while first > 0 and HYPHENATED.fullmatch(out[first - 1][1]) and not is_type(out[first - 1][1]):
                (at, before), after = out[first - 1], (out[first][1] if first < len(out) else para)
                verdict = joins(before, after, known, inside_word=False)
                if verdict is None and problems is not None:
                    problems.append(
                        f"line {at}: {before!r} / {after!r} before a type cell: a name wrapped inside a "
                        "word (not one the spec knows), or a cell and a name; not joined"
                    )
                if not verdict:
                    break
                first -= 1
            if first < len(out):
                para = "".join([*(c.removesuffix("-") for _, c in out[first:]), para])
                number = out[first][0]
                del out[first:]
        out.append((number, para))
    return out


def _tables(
    paras: list[tuple[int, str]], starts: StartsRow, problems: list[str] | None, notes: list[str] | None
) -> list[Table]:
    running = running_lines([p for _, p in paras])
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
            if current is not None:  # the heading above this header, and what follows it, are not its
                at = [k for k, (_, cells) in enumerate(current.rows) if cells[0] == heading]
                del current.rows[at[-1] if at else len(current.rows) :]
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
        if is_page_line(para) or (current is not None and para in running):
            if current is not None and is_page_line(para):
                after = skip_page_break(paras, i, current, running, starts, problems, notes)
                if after is None:
                    current = None  # the next section starts on the next page
                else:
                    i = after
                    continue
            i += 1
            continue
        if "input" in para.lower() or "output" in para.lower():
            if len(para) <= 60 and not para.endswith("."):
                heading = para
        if current is not None:
            current.rows.append((number, [para]))
            count += 1
            check_rows(count, number)
        i += 1
    if current is not None:
        current.open_end = True
    return tables


def _end(table: Table, starts: StartsRow) -> None:
    """Where the table ends: after its last row's comment (more paragraphs of it while they are
    sentences, not titles) and version; what follows is the document's next part. When the text
    ends inside the table, a row started but not whole is kept as its `stub`."""
    flat = table.rows
    last = next((k for k in range(len(flat) - 2, -1, -1) if starts(flat[k][1][0], flat[k + 1][1][0])), None)
    if last is None:
        if table.open_end and flat:
            table.stub = (flat[0][0], flat[0][1][0])
        return
    k = last + 2
    if k < len(flat) and not is_version_text(flat[k][1][0]) and not is_placeholder(flat[k][1][0]):
        k += 1  # the comment
        while k < len(flat) and not (
            is_version_text(flat[k][1][0]) or is_heading(flat[k][1][0]) or is_placeholder(flat[k][1][0])
        ):
            k += 1  # more paragraphs of it
    if k < len(flat) and is_version_text(flat[k][1][0]):
        k += 1
    if k < len(flat) and is_placeholder(flat[k][1][0]):
        k += 1
    rest = flat[k:]
    del flat[k:]
    if table.open_end and rest:
        first = rest[0][1][0]
        table.open_end = len(rest) <= 3 and bool(FRAGMENT.fullmatch(first)) and "_" in first
        if table.open_end:  # the copy stops in a row: its name, maybe its type
            table.stub = (rest[0][0], " ".join(c[0] for _, c in rest))
