"""The guide's PDF as `pdftotext` (no `-layout`) gives it: a table cell per paragraph, names wrapped.

pdftotext prints each block of text as a paragraph, blank lines between: a table cell is one,
its lines the cell's wrapped lines ("actual_joint_" / "voltage", "5.23.0 /" / "10.11.0"),
and cells standing close share a line ("VECTOR6D Target joint positions", "speed_slider_fraction
DOUBLE"). Here the paragraphs become the one-cell-per-line form `rendered_text` reads.

It also moves cells it cannot place in the page's flow (often a sparse column's: the versions,
comments of rows whose other cells are empty) to the end of the page or between other rows, where
nothing tells whose they are. So the reading is always said to be unsure (a problem: --check
fails, --write refuses; `pdftotext -layout` keeps the columns), and each cell seen out of its
place is reported with its line.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Collection

from rtde_spec.importers.rows import is_version_text
from rtde_spec.importers.tables import FORM_FEED, is_page_mark, split_form_feeds
from rtde_spec.importers.wrapped import FRAGMENT, join_parts, join_text

#: the header cells as paragraphs of their own (blank lines between): pdftotext's blocks
_PARAGRAPH_HEAD = re.compile(r"^[ \t]*Name[ \t]*\n[ \t]*\n[ \t]*Type[ \t]*\n[ \t]*\n[ \t]*Comment", re.M)
_HEADER_CELLS = {"name", "type", "comment", "introduced in version", "version", "since"}
ADVICE = "convert the PDF with `pdftotext -layout`, which keeps the columns"


def is_pdftotext(text: str) -> bool:
    """pdftotext's plain output: form feeds between pages, the header cells as paragraphs."""
    return FORM_FEED in text and bool(_PARAGRAPH_HEAD.search(text))


def _paragraphs(text: str) -> list[tuple[int, list[str]]]:
    """(first line, lines) of each paragraph; a form feed is a paragraph of its own."""
    out: list[tuple[int, list[str]]] = []
    current: list[str] = []
    start = 0
    for number, raw in split_form_feeds(text):
        line = raw.strip(" \t\r")
        if line == FORM_FEED or not line:
            if current:
                out.append((start, current))
            current = []
            if line == FORM_FEED:
                out.append((number, [FORM_FEED]))
            continue
        if not current:
            start = number
        current.append(line)
    if current:
        out.append((start, current))
    return out


class _Cells:
    """The cells found so far, each with what it is (name, type, comment, version, header, other)."""

    def __init__(self) -> None:
        self.cells: list[tuple[int, str]] = []
        self.kinds: list[str] = []

    def add(self, line: int, text: str, kind: str) -> None:
        self.cells.append((line, text))
        self.kinds.append(kind)

    @property
    def last(self) -> str:
        return self.kinds[-1] if self.kinds else ""


def cells(
    text: str, known: Collection[str], is_type: Callable[[str], bool], problems: list[str] | None
) -> list[tuple[int, str]]:
    """The document's cells, one per entry, in pdftotext's order; what cannot be trusted goes to
    `problems` (with the first table's line, and the line of every cell seen out of place)."""
    said: list[str] = []
    found = _Cells()
    types = r"|".join(sorted((re.escape(t) for t in type_words(text, is_type)), key=len, reverse=True))
    starts = re.compile(rf"^(?:([A-Za-z_][A-Za-z0-9_]*)\s+)?({types})(?:\s+(.*))?$") if types else None
    for start, lines in _paragraphs(text):
        _paragraph(start, lines, found, known, starts, said)
    for i in range(len(found.kinds) - 1):  # a one-word name ("payload") before its type
        if (
            found.kinds[i] == "other"
            and found.kinds[i + 1] == "type"
            and FRAGMENT.fullmatch(found.cells[i][1])
        ):
            found.kinds[i] = "name"
    drop = _check_order(found, said)
    head = next((n for (n, c), k in zip(found.cells, found.kinds, strict=True) if k == "header"), 1)
    if problems is not None:
        problems.append(
            f"line {head}: pdftotext's plain output (no -layout) does not keep table cells in their "
            "rows (it prints cells it cannot place at a page's end or between rows): the names and "
            f"types are read, but a comment or version may be another row's; {ADVICE}"
        )
        problems.extend(said)
    return [cell for i, cell in enumerate(found.cells) if i not in drop]


def type_words(text: str, is_type: Callable[[str], bool]) -> set[str]:
    """The words of the text that are type names (UINT32, VECTOR6D): the types a cell may start with."""
    return {w for w in set(re.findall(r"\b[A-Z][A-Z0-9]+\b", text)) if is_type(w)}


def _paragraph(
    start: int,
    lines: list[str],
    found: _Cells,
    known: Collection[str],
    starts: re.Pattern[str] | None,
    said: list[str],
) -> None:
    """One paragraph as cells: a wrapped name rejoined, a type sharing its line split off, a
    comment's or version's lines joined; other text (titles, prose) a line per cell."""
    joined = join_text(lines)
    first = starts.match(lines[0]) if starts is not None else None
    if lines == [FORM_FEED] or (len(lines) == 1 and is_page_mark(lines[0])):
        found.add(start, lines[0], "page")
    elif first is not None:
        name, type_, rest = first.groups()
        if name:
            if name.endswith("_"):
                said.append(
                    f"line {start}: the name {name!r} wraps, and its type shares its line: the rest of "
                    f"the name cannot be told from the comment; {ADVICE}"
                )
            found.add(start, name, "name")
        found.add(start, type_, "type")
        comment = join_text([rest or "", *lines[1:]])
        if comment:
            _comment(start, lines, comment, found, said)
    elif joined.lower() in _HEADER_CELLS or (lines[-1] == "Name" and len(lines) > 1):
        for k, line in enumerate(lines if lines[-1] == "Name" else [joined]):
            found.add(start + k, line, "header" if line.lower() in _HEADER_CELLS else "other")
    elif all(FRAGMENT.fullmatch(p) for p in lines[:1]) and (len(lines) > 1 or "_" in lines[0]):
        if not all(FRAGMENT.fullmatch(p) or p.startswith("(") for p in lines):
            for k, line in enumerate(lines):
                found.add(start + k, line, "other")
            return
        names, unsure = join_parts(lines, known)
        for k in unsure:
            said.append(
                f"line {start + k}: {lines[k - 1]!r} / {lines[k]!r} in one name cell: a name wrapped "
                "inside a word (not one the spec knows) or two names; not joined"
            )
        for name in names:
            found.add(start, name, "name")
    elif is_version_text(joined):
        found.add(start, joined, "version")
    elif found.last == "type":
        _comment(start, lines, joined, found, said)
    else:
        for k, line in enumerate(lines):
            found.add(start + k, line, "other" if not k else "more")


def _comment(start: int, lines: list[str], comment: str, found: _Cells, said: list[str]) -> None:
    """A comment paragraph; a version on a line of its own inside it is another cell pdftotext
    merged in (the row's version, or another row's comment and version): reported."""
    inside = [k for k, line in enumerate(lines) if is_version_text(line)]
    if inside and len(lines) > 1:
        said.append(
            f"line {start + inside[0]}: {lines[inside[0]]!r} inside the text of a comment: cells "
            "pdftotext merged; whose version it is cannot be told"
        )
    found.add(start, comment, "comment")


def _check_order(found: _Cells, said: list[str]) -> set[int]:
    """Cells out of a row's order (name, type, one comment, then one version) while rows follow: a
    name with no type after it, a second comment or a text after the version; and a version no row
    can take. Each is reported; the indices of the cells not to read are returned. Cells after a
    page mark are `page_break`'s to judge."""
    kinds, cells = found.kinds, found.cells
    row_later = [False] * (len(kinds) + 1)  # a row starts at or after i, in the same table
    for i in range(len(kinds) - 1, -1, -1):
        starts = kinds[i] == "name" and i + 1 < len(kinds) and kinds[i + 1] == "type"
        first = i
        while first > 0 and kinds[i] == "header" and kinds[first - 1] == "header":
            first -= 1
        repeated = kinds[i] == "header" and "page" in kinds[max(0, first - 4) : first]  # on the next page
        row_later[i] = starts or ((kinds[i] != "header" or repeated) and row_later[i + 1])
    drop: set[int] = set()
    state = ""
    for i, kind in enumerate(kinds):
        line, text = cells[i]
        if kind == "name":
            if i + 1 < len(kinds) and kinds[i + 1] != "type" and row_later[i + 1]:
                said.append(f"line {line}: the name {text!r} has no type cell after it: not read as a row")
            state = "name"
        elif kind in ("type", "page") or (kind == "header" and text.lower() == "name"):
            state = kind
        elif kind == "header" and state in ("type", "comment", "version"):
            state = "apart"  # a header cell amid the rows (pdftotext moved it): so are the cells after it
        elif kind in ("comment", "version", "other", "more") and state == "apart":
            if i + 1 < len(kinds) and kinds[i + 1] == "header" and cells[i + 1][1].lower() == "name":
                state = ""  # the next table's title
            elif kind != "more":
                said.append(
                    f"line {line}: {text[:60]!r} after a header cell amid the rows: a cell "
                    "pdftotext printed apart from its row; not read"
                )
            if state:
                drop.add(i)
        elif kind in ("comment", "version", "other") and state in ("type", "comment", "version"):
            fits = (state == "type" and kind != "other") or (state == "comment" and kind == "version")
            if not fits and (row_later[i] or kind == "version"):
                said.append(
                    f"line {line}: {text[:60]!r} comes where the row above has no cell left: a cell "
                    "pdftotext printed apart from its row; not read"
                )
                drop.add(i)
                drop.update(
                    range(i + 1, next((j for j in range(i + 1, len(kinds)) if kinds[j] != "more"), i + 1))
                )
                continue
            state = kind if kind != "other" else "comment"
    return drop
