"""The guide as an HTML page: tables read with the standard library's HTML parser.

Headings (h1-h6) before a table say which direction it lists; a row's line is the
line of its <tr> in the page source.
"""

from __future__ import annotations

from html.parser import HTMLParser

from rtde_spec.spec.importers.tables import Table

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

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in _HEADINGS:
            self._heading_text = []
        elif tag == "table":
            self._depth += 1
            if self._depth == 1:
                self._table = Table(self.heading, [], self.getpos()[0])
        elif self._depth == 1 and tag == "tr":
            self._close_row()  # </tr> and </td> may be left out in HTML
            self._row, self._row_line = [], self.getpos()[0]
        elif self._depth == 1 and tag in ("td", "th") and self._row is not None:
            self._close_cell()
            self._cell = []
        elif tag == "br" and self._cell is not None:
            self._cell.append(" ")

    def handle_endtag(self, tag: str) -> None:
        if tag in _HEADINGS and self._heading_text is not None:
            self.heading = " ".join("".join(self._heading_text).split())
            self._heading_text = None
        elif tag == "table":
            if self._depth == 1:
                self._close_row()
            if self._depth == 1 and self._table is not None:
                self.tables.append(self._table)
                self._table = None
            self._depth = max(0, self._depth - 1)
        elif self._depth == 1 and tag in ("td", "th"):
            self._close_cell()
        elif self._depth == 1 and tag == "tr":
            self._close_row()

    def _close_cell(self) -> None:
        if self._cell is not None and self._row is not None:
            self._row.append(" ".join("".join(self._cell).split()))
        self._cell = None

    def _close_row(self) -> None:
        self._close_cell()
        if self._row is not None and self._table is not None:
            if not self._table.header:
                self._table.header = self._row
            elif any(self._row):
                self._table.rows.append((self._row_line, self._row))
        self._row = None

    def handle_data(self, data: str) -> None:
        if self._heading_text is not None:
            self._heading_text.append(data)
        if self._cell is not None:
            self._cell.append(data)


def read_tables(text: str) -> list[Table]:
    reader = _Reader()
    reader.feed(text)
    reader.close()
    return reader.tables
