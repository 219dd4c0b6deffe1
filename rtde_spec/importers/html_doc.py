"""The guide as an HTML page: tables read with the standard library's HTML parser.

Headings (h1-h6) before a table say which direction it lists; a row's line is the
line of its <tr> in the page source. The page is first reduced, in one linear pass, to
the tags that matter here (every other tag, comment and stray `<` dropped), because
html.parser rescans unclosed markup: `<table>` and 200k `<a` took two minutes, and
`<![` ended in its own AssertionError.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser

from rtde_spec.errors import UsageError
from rtde_spec.importers.cells import visible
from rtde_spec.importers.tables import Table, check_rows

_KEEP = re.compile(r"</?(?:table|tr|td|th|h[1-6]|br|p|li|div|sup)\b[^<>]*>", re.I)
_TAG = re.compile(r"<[^<>]*>")

_HEADINGS = {"h1", "h2", "h3", "h4", "h5", "h6"}


class _Reader(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tables: list[Table] = []
        self.heading = ""
        self._heading_text: list[str] | None = None
        self._table: Table | None = None
        self._row: list[str] | None = None
        self._row_line = 0
        self._cell: list[str] | None = None
        self._depth = 0  # nested tables are read as text of their cell
        self._count = 0
        self._sup = 0  # inside <sup>: a footnote marker when in a name cell (actual_q<sup>1</sup>)
        self._para: list[str] | None = None  # a <p> outside tables: a title where a page has no <h3>
        self.title = ""  # the last short <p> after the last heading, before a table
        self._title = ""  # the one before the table being read

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in _HEADINGS:
            self._heading_text = []
        elif tag == "p" and self._depth == 0:
            self._para = []
        elif tag == "table":
            self._depth += 1
            self._para = None  # a <p> left open ends at the table, as a browser ends it
            if self._depth == 1:
                self._table = Table(self.heading, [], self.getpos()[0])
                self._title, self.title = self.title, ""  # used once: a second table needs its own
        elif self._depth == 1 and tag == "tr":
            self._close_row()  # </tr> and </td> may be left out in HTML
            self._row, self._row_line = [], self.getpos()[0]
        elif self._depth == 1 and tag in ("td", "th") and self._row is not None:
            self._close_cell()
            self._cell = []
        elif tag == "br" and self._cell is not None:
            self._cell.append(" ")
        elif tag == "sup":
            self._sup += 1

    def handle_endtag(self, tag: str) -> None:
        if tag in _HEADINGS and self._heading_text is not None:
            self.heading = " ".join("".join(self._heading_text).split())
            self._heading_text = self._para = None
            self.title = ""
        elif tag == "p" and self._para is not None:
            text = " ".join("".join(self._para).split())
            if 0 < len(text) <= 60 and not text.endswith("."):
                self.title = text
            self._para = None
        elif tag == "table":
            if self._depth == 1:
                self._close_row()
            if self._depth == 1 and self._table is not None:
                self.tables.append(self._table)
                self._table = None
            self._depth = max(0, self._depth - 1)
        elif tag == "sup":
            self._sup = max(0, self._sup - 1)
        elif self._depth == 1 and tag in ("td", "th"):
            self._close_cell()
        elif self._depth == 1 and tag == "tr":
            self._close_row()

    def _close_cell(self) -> None:
        if self._cell is not None and self._row is not None:
            self._row.append(" ".join(visible("".join(self._cell)).split()))
        self._cell = None

    def _close_row(self) -> None:
        self._close_cell()
        if self._row is not None and self._table is not None:
            if not self._table.header:
                self._table.header = self._row
                self._table.heading = self._table_heading(self._table)
            elif any(self._row):
                self._table.rows.append((self._row_line, self._row))
                self._count += 1
                check_rows(self._count, self._row_line)
        self._row = None

    def _table_heading(self, table: Table) -> str:
        """The heading above a field table; a short <p> title after it when only that names the
        direction (a CMS or word-processor page: <p><strong>Robot Controller Outputs</strong></p>).
        Other tables (the primary interface's, titled by their heading) keep the heading."""
        said = Table(self._title, [], 0).direction
        if table.is_field_table and said and table.direction is None:
            return self._title
        return table.heading

    def handle_data(self, data: str) -> None:
        if self._para is not None:
            self._para.append(data)
        if self._heading_text is not None:
            self._heading_text.append(data)
        if self._cell is not None and not (
            self._sup and self._row == [] and self._table and self._table.header
        ):
            self._cell.append(data)  # a <sup> in a row's first (name) cell is a footnote marker, dropped


def _drop_comments(text: str) -> str:
    """Comments and CDATA/declarations out, newlines kept (lines stay right); linear in the text."""
    out: list[str] = []
    pos = 0
    while True:
        start = text.find("<!", pos)
        if start < 0:
            out.append(text[pos:])
            return "".join(out)
        out.append(text[pos:start])
        end_mark = "-->" if text.startswith("<!--", start) else ">"
        end = text.find(end_mark, start + 2)
        stop = len(text) if end < 0 else end + len(end_mark)
        out.append("\n" * text.count("\n", start, stop))
        pos = stop


def simplify(text: str) -> str:
    """Only the tags a table reader needs, each well formed; other markup removed, lines kept."""

    def tag(m: re.Match[str]) -> str:
        if _KEEP.fullmatch(m.group(0)):
            return m.group(0)
        return "\n" * m.group(0).count("\n")

    body = _TAG.sub(tag, _drop_comments(text))
    return _escape(body)


def _escape(body: str) -> str:
    """A `<` that starts no kept tag is text."""
    out: list[str] = []
    pos = 0
    for m in _KEEP.finditer(body):
        out.append(body[pos : m.start()].replace("<", "&lt;"))
        out.append(m.group(0))
        pos = m.end()
    out.append(body[pos:].replace("<", "&lt;"))
    return "".join(out)


def read_tables(text: str, problems: list[str] | None = None) -> list[Table]:
    """The page's tables; one the page ends inside (a download cut short) is kept with the rows
    read, and said in `problems`: its rows after the cut are missing, not removed."""
    reader = _Reader()
    try:
        reader.feed(simplify(text))
        reader.close()
    except UsageError:
        raise
    except Exception as exc:  # html.parser's own assertion on markup it cannot read
        raise UsageError(f"the HTML could not be read: {type(exc).__name__}: {exc}") from None
    table = reader._table
    if table is not None and table.header:  # a <table> cut before its first row holds nothing
        # the row the page stops in may have lost its last cells (VECTOR6D cut to VECTOR): dropped
        partial = reader._row is not None
        partial_line = reader._row_line
        reader._row = reader._cell = None
        table.cut = True
        reader.tables.append(table)
        if problems is not None:
            dropped = f"; the row at line {partial_line} it stops in is not read" if partial else ""
            problems.append(
                f"the page ends inside the table {table.heading or 'without a heading'!r} (<table> at "
                f"line {table.line} is never closed, {len(table.rows)} rows read{dropped}): a download "
                "cut short; the spec's fields after the cut are not reported as removed"
            )
    return reader.tables
