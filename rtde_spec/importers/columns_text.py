"""The guide's PDF as `pdftotext -layout` gives it: a table as columns aligned with spaces.

A row is a line whose first word (at the Name column) is followed by a type (at the Type
column); the lines under it, up to a blank line, continue its cells: what stands left of the
Type column continues the name (wrapped at its `_`: see `wrapped`), what stands in the
Introduced column continues the version, the rest the comment. Columns are taken from the
header line (`Name  Type  Comment  Introduced`), which may sit a character or two apart on
another page. A page's furniture (page number, running title, the header again) is skipped and
the table goes on; lines in the comment column right after a page break are the last row's,
split over the page. A line at the left margin that is no row ends the table.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Collection
from dataclasses import dataclass, field

from rtde_spec.importers.page_break import is_furniture
from rtde_spec.importers.pdf_plain import type_words
from rtde_spec.importers.rows import is_version_text
from rtde_spec.importers.tables import (
    FORM_FEED,
    Table,
    check_rows,
    continues,
    is_heading,
    is_page_mark,
    running_lines,
    split_form_feeds,
)
from rtde_spec.importers.wrapped import FRAGMENT, join_parts, join_text

#: the header line of a field table, its cells apart by two spaces or more
HEAD = re.compile(
    r"^(?P<lead>[ \t]*)Name[ \t]{2,}(?P<type>Type)[ \t]{2,}Comment\b"
    r"(?:[ \t]{2,}(?P<version>Introduced|Version|Since)\b)?",
    re.I,
)
#: the same, anywhere in a document: how the form is told
SIGN = re.compile(r"^[ \t]*Name[ \t]{2,}Type[ \t]{2,}Comment\b", re.M)
#: what the header's wrapped last cell leaves on the lines under it
_HEAD_TAIL = re.compile(r"(?:in\s+)?(?:version|in)", re.I)
_SLACK = 4  # how far (characters) a cell may stand from its column on another page


@dataclass
class _Row:
    line: int
    name: list[str]
    type: str
    comment: list[str] = field(default_factory=list)
    version: list[str] = field(default_factory=list)


@dataclass
class _Columns:
    name: int
    type: int
    version: int | None

    def shifted(self, lead: int) -> _Columns:
        """The columns of a page whose rows start at `lead` (pdftotext moves a page's grid)."""
        d = lead - self.name
        return _Columns(lead, self.type + d, None if self.version is None else self.version + d)


def _chunks(line: str, start: int = 0) -> list[tuple[int, str]]:
    """(column, text) of the runs of words from `start`, apart by two spaces or more."""
    return [(m.start(), m.group(0)) for m in re.finditer(r"\S+(?: \S+)*", line[start:].expandtabs())]


def _split(row: _Row, line: str, cols: _Columns, start: int) -> None:
    """The cells of one line from `start` on, by column: the version's, and the comment's."""
    chunks = [(x + start, t) for x, t in _chunks(line, start)]
    if chunks and cols.version is not None:
        x, text = chunks[-1]
        if x >= cols.version - 2 or (x >= cols.version - _SLACK and is_version_text(text)):
            row.version.append(text)
            chunks.pop()
    row.comment += [t for _, t in chunks]


class _Reader:
    def __init__(self, text: str, types: str, known: Collection[str], problems: list[str] | None) -> None:
        self.lines = split_form_feeds(text)
        self.running = running_lines([t for _, t in self.lines])
        self.row_re = re.compile(
            rf"^(?P<lead>\s*)(?P<name>[A-Za-z_][\w{{}}]*(?:\s\([^)]*\))?)\s+({types})(?=\s|$)"
        )
        self.known = known
        self.problems = problems
        self.tables: list[Table] = []
        self.table: Table | None = None
        self.cols = _Columns(0, 0, None)
        self.row: _Row | None = None
        self.split = False  # a page broke the open row: its name may go on at the top of the next page
        self.type_re = re.compile(rf"\s*({types})(?=\s|$)")
        self.heading = ""
        self.count = 0

    def flush(self) -> None:
        row, self.row = self.row, None
        if row is None or self.table is None:
            return
        if not row.name:
            self._say(
                f"line {row.line}: a row of type {row.type} without its name (printed where no row "
                "can claim it): not read"
            )
            return
        names, unsure = join_parts(row.name, self.known)
        for k in unsure:
            self._say(
                f"line {row.line + k}: {row.name[k - 1]!r} / {row.name[k]!r} under one name: wrapped "
                "inside a word (not a name the spec knows) or two names; read as the first"
            )
        cells = [names[0], row.type, join_text(row.comment), join_text(row.version)]
        self.table.rows.append((row.line, cells if cells[3] else cells[:3]))
        self.count += 1
        check_rows(self.count, row.line)

    def _say(self, problem: str) -> None:
        if self.problems is not None:
            self.problems.append(problem)

    def read(self) -> list[Table]:
        in_row = header_tail = broken = page_top = False
        for number, raw in self.lines:
            line, text = raw.rstrip(), raw.strip()
            if raw == FORM_FEED:
                broken = page_top = True
                in_row = header_tail = False
                continue
            if not text:
                in_row = header_tail = False
                continue
            if (head := HEAD.match(line)) is not None:
                self._header(number, head, continued=broken and self.table is not None)
                header_tail, broken, page_top = True, self.table is not None and broken, False
                continue
            if header_tail and _HEAD_TAIL.fullmatch(text):
                continue
            header_tail = False
            if is_page_mark(text) or text in self.running:
                broken = broken or is_page_mark(text)
                self.split = self.split or (broken and self.row is not None)
                page_top = False
                continue
            lead = len(line) - len(line.lstrip())
            if self._row_starts(number, line, lead, broken):
                in_row, broken, page_top = True, False, False
                continue
            if page_top or (broken and self._furniture(text)):
                page_top = False  # the running title, a heading "(continued)" or naming a direction
                continue
            if self.row is not None and (
                in_row or lead > self.cols.name + _SLACK or (self.split and self._name_goes_on(line))
            ):
                if self._go_on(number, line):
                    in_row = True
                    continue
            self._outside(number, text, lead)
            in_row = False
        self.flush()
        if self.table is not None:
            self.table.open_end = not broken  # a page's end after it: the document's end, not a cut
        return self.tables

    def _row_starts(self, number: int, line: str, lead: int, broken: bool) -> bool:
        """Start a row at this line when it is one: a name at the Name column, a type at the Type
        column (the columns of a new page found from its first row)."""
        row = self.row_re.match(line) if self.table is not None else None
        if row is None or lead > self.cols.name + _SLACK:
            return False
        cols = self.cols.shifted(lead) if broken else self.cols
        if row.start(3) - cols.type > _SLACK:  # left of it: a long name pushed a squeezed line's type
            return False
        self.cols = cols
        self.flush()
        self.row = _Row(number, [row["name"]], row[3])
        self.split = False
        _split(self.row, line, self.cols, row.end(3))
        return True

    def _name_goes_on(self, line: str) -> bool:
        """After a page break, a piece of a name at the Name column: the rest of the open row's
        name, when it has none yet (pdftotext put it on the next page) or ends in `_`."""
        assert self.row is not None
        name = line[: max(0, self.cols.type - 1)].strip()
        return bool(FRAGMENT.fullmatch(name)) and (not self.row.name or self.row.name[-1].endswith("_"))

    def _furniture(self, text: str) -> bool:
        """After a page break: a line the page puts there, unless it starts the next section."""
        return (
            self.table is not None
            and continues(self.table, [FORM_FEED, text])
            and is_furniture(text, self.running)
        )

    def _header(self, number: int, head: re.Match[str], continued: bool) -> None:
        lead = len(head["lead"].expandtabs())
        cols = _Columns(lead, head.start("type"), head.start("version") if head["version"] else None)
        if continued:  # the header repeated at the top of the next page
            self.cols = cols
            return
        self.flush()
        self.cols = cols
        cells = ["Name", "Type", "Comment", *(["Introduced in version"] if head["version"] else [])]
        self.table = Table(self.heading, cells, number)
        self.tables.append(self.table)

    def _go_on(self, number: int, line: str) -> bool:
        """Continue the row's cells with this line; False when it is no part of the row (a title
        at the left margin)."""
        assert self.row is not None
        cut = min(self.cols.type - 1, len(line))
        while 0 < cut < len(line) and not line[cut - 1].isspace() and not line[cut].isspace():
            cut -= 1  # a word that straddles the column starts left of it: the name's
        name = line[:cut].strip()
        if name and not (FRAGMENT.fullmatch(name) or name.startswith("(")):
            return False
        typed = self.type_re.match(line, cut)
        if not name and typed is not None and abs(typed.start(1) - self.cols.type) <= _SLACK:
            self.flush()  # a row whose name cell pdftotext printed elsewhere (on the next page)
            self.row = _Row(number, [], typed[1])
            self.split = False
            _split(self.row, line, self.cols, typed.end(1))
            return True
        if name:
            self.row.name.append(name)
        _split(self.row, line, self.cols, cut)
        return True

    def _outside(self, number: int, text: str, lead: int) -> None:
        """A line that is no row: a title or prose, which ends the table; a row after the table's
        end is reported, never dropped silently."""
        if self.table is not None and lead <= self.cols.name + _SLACK:
            self.flush()
            self.table = None
        elif self.table is None and self.tables and self.row_re.match(text):
            self._say(
                f"line {number}: {text[:60]!r} looks like a row of the table above, after its end: not read"
            )
        if is_heading(text) and ("input" in text.lower() or "output" in text.lower()):
            self.heading = text


def read_tables(
    text: str, is_type: Callable[[str], bool], known: Collection[str] = (), problems: list[str] | None = None
) -> list[Table]:
    """The field tables of a `pdftotext -layout` text, a row per entry with its four cells."""
    types = "|".join(sorted((re.escape(t) for t in type_words(text, is_type)), key=len, reverse=True))
    return _Reader(text, types or r"(?!)", known, problems).read()
