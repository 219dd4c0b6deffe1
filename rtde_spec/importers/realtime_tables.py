"""The real-time interface's tables (port 30003): Meaning | Type | Number of values | Size in bytes.

UR publishes one table per edition ("RealTime 5.10" on the docs site and in the manual, the
client-interface workbook's "RealTime_3.2" sheet), a row per quantity, then a TOTAL row
with the values and bytes of the whole message. The copies differ in small ways read here:
the Message Size row has no Gnuplot column, the rows UR keeps for itself have no name,
the notes run over several cells (a link to "Robot Modes"), and the rendered page puts
every cell in a paragraph of its own.
"""

from __future__ import annotations

import re

from rtde_spec.importers.cells import Lines, full_version
from rtde_spec.importers.model import DocRealtimeRow, DocRealtimeTable
from rtde_spec.importers.tables import Table, check_rows

HEAD = ("meaning", "type", "number of values")
#: the type words the tables use, and how the spec's primitives spell them
TYPES = {"double": "double", "integer": "int32", "int": "int32", "int32": "int32", "uint64": "uint64"}
_INT = re.compile(r"^\d+$")
_COLUMN = re.compile(r"^\d+(\s*-\s*\d+)?$")
_VERSION = re.compile(r"(\d+)\.(\d+)(?:\.(\d+))?")
#: a row standing for rows left out
_ELLIPSIS = re.compile(r"…|\.\.\.|\band more\b", re.I)


def is_placeholder(cell: str) -> bool:
    return bool(_ELLIPSIS.search(cell)) and len(cell) <= 60


def _clean(cell: str) -> str:
    return " ".join(cell.replace("\u00a0", " ").split()).rstrip("|").strip()


def is_header(cells: list[str]) -> bool:
    """Whether a row (or three paragraphs) is the head of a real-time table."""
    return tuple(_clean(c).lower() for c in cells if _clean(c))[:3] == HEAD


def key(name: str) -> str:
    """A row's name as the spec spells fields: "Tool vector actual" -> tool_vector_actual."""
    return re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")


def is_type(cell: str) -> bool:
    return _clean(cell).lower() in TYPES


def edition_of_title(title: str, lines: Lines) -> tuple[str | None, str | None]:
    """(version, product line) a table's title names: "RealTime 5.10" -> 5.10.0 on e-series.

    "3.0 and 3.1" is the message of both (the newest is taken); "Pre-3.0" names no version
    of a product line: (None, None).
    """
    if re.search(r"\bpre[- _]?\d", title, re.I):
        return None, None
    found = [m.group(0) for m in _VERSION.finditer(title)]
    if not found:
        return None, None
    version = max((full_version(v) for v in found), key=lambda v: tuple(int(p) for p in v.split(".")))
    return version, lines.line_of(version)


def parse_row(cells: list[str], number: int) -> DocRealtimeRow | tuple[int, int] | None:
    """A row of cells: a field row, the TOTAL row's (values, bytes), or None when it is neither."""
    cells = [_clean(c) for c in cells]
    if not any(cells):
        return None
    cells = [cells[0], *(c for c in cells[1:] if c)]  # merged cells read as empty ones between
    if cells[0].upper() == "TOTAL":
        ints = [int(c) for c in cells[1:3] if _INT.match(c)]
        return (ints[0], ints[1]) if len(ints) == 2 else None
    for at in (0, 1):
        if (
            len(cells) >= at + 3
            and is_type(cells[at])
            and _INT.match(cells[at + 1])
            and _INT.match(cells[at + 2])
            and (at == 0 or not is_type(cells[0]))
        ):
            name = cells[0] if at == 1 else ""
            rest = cells[at + 3 :]
            column = rest.pop(0) if rest and _COLUMN.match(rest[0]) else ""
            doc = " ".join(c for c in rest if c)
            return DocRealtimeRow(
                name,
                key(name),
                cells[at].lower(),
                int(cells[at + 1]),
                int(cells[at + 2]),
                doc,
                number,
                column,
            )
    return None


def table_of(table: Table, lines: Lines, title: str | None = None) -> DocRealtimeTable:
    """A real-time table read into rows, its header (Message Size) and its TOTAL."""
    name = title or table.heading
    edition, line = edition_of_title(name, lines)
    out = DocRealtimeTable(name, table.line, edition, line)
    for number, cells in table.rows:
        if not any(c.strip() for c in cells):
            continue
        got = parse_row(cells, number)
        if isinstance(got, tuple):
            out.total = got
            break  # the TOTAL row ends the table; notes follow it
        if got is None:
            first = next(c for c in cells if c.strip()).strip()
            if is_placeholder(first):
                out.skipped.append((number, first[:60]))
            elif _clean(cells[0]).upper() == "TOTAL" or any(
                is_type(c) for c in [_clean(c) for c in cells if c.strip()][:2]
            ):
                out.unread.append((number, _clean(cells[0]) or first[:60]))  # its numbers are empty
                if _clean(cells[0]).upper() == "TOTAL":
                    break
            continue
        if got.key == "message_size" and not out.rows:
            out.header.append(got)
        else:
            out.rows.append(got)
    return out


def tables_in(tables: list[Table], lines: Lines, title: str | None = None) -> list[DocRealtimeTable]:
    """The real-time tables among a document's tables."""
    return [table_of(t, lines, title) for t in tables if is_header(t.header)]


def _is_title(text: str) -> bool:
    return 0 < len(text) <= 60 and not text.endswith((".", ")", ":")) and not text.startswith("(")


#: what a PDF's pages print between table rows: page numbers, running heads, the copyright line
_PAGE_MARK = re.compile(r"^(?:-\d+-|Chapter \d+|G3/G5|Copyright ©.*|\f.*)$")


def joined_cells(text: str) -> str:
    """The PDF's text (pdftotext): cells are paragraphs, and a long cell wraps over adjacent
    lines ("Number of" / "values", "Tool vector" / "actual"): one line per paragraph, except
    that a paragraph ending in the header's first cell keeps its title lines apart from it.

    pdftotext also prints a row's name cell out of order, after the page's last row (before
    its page mark): such a name goes back to the unnamed row of that page whose notes it
    repeats ("Tool Accelerometer values" -> "Tool x,y and z accelerometer values")."""
    out: list[str] = []
    page_ends: list[int] = []
    for para in re.split(r"\n[ \t]*\n", text):
        rows = [r.strip() for r in para.splitlines() if r.strip() and not _PAGE_MARK.match(r.strip())]
        if not rows:
            if para.strip():
                page_ends.append(len(out))
            continue
        if len(rows) > 1 and rows[-1].lower() == "meaning":
            out += rows
        else:
            out.append(" ".join(rows))
    start = 0
    for end in page_ends:
        _restore_name(out, start, end)
        start = end
    return "\n\n".join(out)


def _words(text: str) -> set[str]:
    return set(re.findall(r"[a-z0-9]+", text.lower()))


def _is_name_cell(cell: str) -> bool:
    return (
        0 < len(cell) <= 40
        and not is_type(cell)
        and not _COLUMN.match(cell)
        and not cell.endswith((".", ")", ":"))
        and cell[:1].isupper()
    )


def _restore_name(cells: list[str], start: int, end: int) -> None:
    """Move a name cell printed at the end of a page (before `end`) back to the unnamed row of
    that page (from `start`) whose notes share at least two of its words; else leave it."""
    at = end - 1
    if at <= start or not _is_name_cell(cells[at]) or is_type(cells[at - 1]):
        return
    name = _words(cells[at])
    best, best_score = None, 1
    for k in range(start + 1, at - 3):
        # an unnamed row: a type and two numbers right after the notes of the row before
        if not (is_type(cells[k]) and _INT.match(cells[k + 1]) and _INT.match(cells[k + 2])):
            continue
        if _INT.match(cells[k - 1]) or _COLUMN.match(cells[k - 1]) or len(cells[k - 1].split()) < 4:
            continue
        notes = cells[k + 4] if _COLUMN.match(cells[k + 3]) else cells[k + 3]
        score = len(name & _words(notes))
        if score > best_score:
            best, best_score = k, score
    if best is not None:
        cells.insert(best, cells.pop(at))


#: a chapter heading ("5. Safety Mode Types"): the Notes column links to these by title
_CHAPTER = re.compile(r"^\s*\d+\.\s+([A-Za-z][A-Za-z ]*[A-Za-z])\s*\d*\s*$", re.M)


def chapter_titles(text: str) -> frozenset[str]:
    """The document's chapter titles, lower case: the texts its Notes column links to."""
    return frozenset(m.group(1).lower() for m in _CHAPTER.finditer(text))


def read_paragraphs(text: str, lines: Lines, links: frozenset[str] = frozenset()) -> list[DocRealtimeTable]:
    """The rendered page: every cell a paragraph (or a line ending in `|`), rows found by shape.

    A row starts at a name followed by a type and two whole numbers, or, for the rows UR
    leaves unnamed, at a type followed by two numbers once the row before has its notes.
    A chapter's title (`links`: "Safety Mode Types") after a row whose notes hold no link yet
    is that row's link, not the name of the (unnamed) row after it; a TOTAL printed after its
    two numbers takes them back from the last row's notes.
    """
    paras = [(n, _clean(raw)) for n, raw in enumerate(text.splitlines(), start=1)]
    paras = [(n, p) for n, p in paras if p and not re.fullmatch(r"[-|: ]+", p)]
    tables: list[Table] = []
    titles: list[str] = []
    current: list[tuple[int, list[str]]] | None = None
    notes = False
    count = 0
    i = 0
    size = len(paras)

    def ints(j: int) -> bool:
        return j + 1 < size and bool(_INT.match(paras[j][1])) and bool(_INT.match(paras[j + 1][1]))

    while i < size:
        number, para = paras[i]
        if i + 2 < size and is_header([para, paras[i + 1][1], paras[i + 2][1]]):
            title_at = next((j for j in range(i - 1, max(-1, i - 4), -1) if _is_title(paras[j][1])), None)
            title = paras[title_at][1] if title_at is not None else ""
            if current and title_at is not None:  # the title (and what follows it) is no note of the last row
                cells = current[-1][1]
                del cells[max(4, len(cells) - (i - title_at)) :]
            current = []
            tables.append(Table(title, [p for _, p in paras[i : i + 3]], number))
            tables[-1].rows = current  # filled below
            titles.append(title)
            i += 3
            while i < size and not (i + 1 < size and is_type(paras[i + 1][1])) and len(paras[i][1]) <= 20:
                i += 1  # the rest of the header: Size in bytes, Gnuplot col., Notes
            notes = True
            continue
        if current is None:
            i += 1
            continue
        if para.upper() == "TOTAL":
            last = current[-1][1] if current else []
            if not ints(i + 1) and len(last) >= 7 and _INT.match(last[-2]) and _INT.match(last[-1]):
                # the PDF's text prints the TOTAL row's numbers before its label
                current.append((number, ["TOTAL", *last[-2:]]))
                del last[-2:]
                current = None
                i += 1
                continue
            current.append((number, [p for _, p in paras[i : i + 4]]))
            current = None
            i += 4
            continue
        named = i + 3 < size and not is_type(para) and is_type(paras[i + 1][1]) and ints(i + 2)
        if (
            named
            and current
            and para.lower() in links
            and not any(c.lower() in links for c in current[-1][1][4:])
        ):
            named = False  # the row above's link to a chapter (its notes have none yet)
        unnamed = is_type(para) and ints(i + 1)
        # the Message Size row (the first, no Gnuplot column) may come without notes (the PDF's
        # text moves its note away): a name, a type and two numbers after it are the next row
        first_bare = len(current) == 1 and len(current[-1][1]) == 4
        if named and (notes or first_bare):
            current.append((number, [para, paras[i + 1][1], paras[i + 2][1], paras[i + 3][1]]))
            i += 4
            notes = False
        elif unnamed:
            current.append((number, ["", para, paras[i + 1][1], paras[i + 2][1]]))
            i += 3
            notes = False
        elif is_placeholder(para):
            current.append((number, [para]))
            i += 1
        elif current:
            current[-1][1].append(para)
            notes = notes or not (_COLUMN.match(para) and len(current[-1][1]) == 5)
            i += 1
        else:
            i += 1
        count += 1
        check_rows(count, number)
    return [table_of(t, lines, title) for t, title in zip(tables, titles, strict=True)]


#: the manual page as a text extractor gives it: the header and every row on one line, spaces between
#: (pdftotext -layout wraps the header's cells under it: "Number of" / "values", "Size in" / "bytes")
SPACED_HEAD = re.compile(
    r"^\s*Meaning\s+Type\s+Number of(?:\s+values)?\s+Size in(?:\s+bytes)?\b", re.I | re.M
)
_SPACED_ROW = re.compile(
    r"^(?P<name>.*?)\s*\b(?P<type>double|integer|int32|uint64)\s+(?P<count>\d+)\s+(?P<size>\d+)"
    r"(?:\s+(?P<column>\d+(?:\s*-\s*\d+)?)(?=\s|$))?\s*(?P<notes>.*)$",
    re.I,
)
_SPACED_TOTAL = re.compile(r"^\s*TOTAL\s+(\d+)\s+(\d+)\b", re.I)


def read_spaced(text: str, lines: Lines) -> list[DocRealtimeTable]:
    """Tables whose header and rows are each one line of space-separated cells ("RealTime 5.9"
    as extracted from the manual's page); a line that is no row continues the notes above.

    In a column layout (pdftotext -layout: cells apart by runs of spaces, a wrapped cell
    continued on the lines below it), the part of a continuation line left of the row's
    Type column continues its name ("Tool vector" / "actual"), the rest its notes; page
    marks between rows are dropped."""
    tables: list[Table] = []
    titles: list[str] = []
    current: Table | None = None
    title = ""
    count = 0
    columns = False
    type_at = 0  # where the last row's Type cell starts, in a column layout
    for number, raw in enumerate(text.splitlines(), start=1):
        line = " ".join(raw.split())
        if not line:
            continue
        if SPACED_HEAD.match(line):
            current = Table(title, HEAD_CELLS, number)
            tables.append(current)
            titles.append(title)
            columns = bool(re.search(r"Meaning {2,}Type", raw))
            continue
        if current is None:
            if _is_title(line):
                title = line
            continue
        if (total := _SPACED_TOTAL.match(line)) is not None:
            current.rows.append((number, ["TOTAL", total.group(1), total.group(2)]))
            current = None
            continue
        if columns and _PAGE_MARK.match(line):
            continue
        row = _SPACED_ROW.match(line)
        if row is not None:
            cells = [row["name"], row["type"], row["count"], row["size"], row["column"] or "", row["notes"]]
            current.rows.append((number, cells))
            found = re.search(rf"\b{re.escape(row['type'])}\b", raw)
            type_at = found.start() if found else 0
            count += 1
            check_rows(count, number)
        elif is_placeholder(line):
            current.rows.append((number, [line]))
        elif current.rows and columns and type_at:
            cells = current.rows[-1][1]
            name, notes = " ".join(raw[:type_at].split()), " ".join(raw[type_at:].split())
            if name and len(cells) >= 6:
                cells[0] = f"{cells[0]} {name}".strip()
            if notes:
                cells.append(notes)
        elif current.rows:
            current.rows[-1][1].append(line)  # a note's link ("Robot Modes") on a line of its own
    return [table_of(t, lines, t_title) for t, t_title in zip(tables, titles, strict=True)]


HEAD_CELLS = ["Meaning", "Type", "Number of values", "Size in bytes", "Gnuplot col.", "Notes"]
