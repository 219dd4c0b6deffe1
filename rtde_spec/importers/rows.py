"""From a guide's field tables to DocFields: names, families, types, versions per range."""

from __future__ import annotations

import re
from collections import Counter

from rtde_spec.importers.cells import (
    DASHES,
    Lines,
    name_text,
    parse_name,
    parse_versions,
    spans_in,
    versions_in_text,
)
from rtde_spec.importers.model import DocField, TableReport
from rtde_spec.importers.tables import Table

#: a row standing for rows left out ("…", "... and more fields ...", "etc."): never a field
_PLACEHOLDER = re.compile(r"…|\.\.\.|\band more\b|\betc\.?$|^\W*$", re.I)


def is_placeholder(name_cell: str) -> bool:
    """Whether a name cell holds no field name but a note that rows were left out."""
    word = name_text(name_cell)  # Markdown copies put names in `code` or **bold**, others in quotes
    return bool(_PLACEHOLDER.search(word)) or not re.match(r"[A-Za-z_]", word)


def field_rows(tables: list[Table], lines: Lines, reports: list[TableReport] | None = None) -> list[DocField]:
    """Every field row of the field tables; per table, what was read and skipped goes to `reports`."""
    out: list[DocField] = []
    for table in tables:
        direction = table.direction
        if not table.is_field_table or direction is None:
            continue
        report = TableReport(table.heading, direction, table.line, cut=table.cut)
        for line, cells in table.rows:
            if not cells or not cells[0].strip():
                continue
            if len(cells) < 2 and not is_placeholder(cells[0]):
                continue
            report.rows += 1
            if is_placeholder(cells[0]):
                report.skipped.append((line, cells[0].strip()[:60]))
                continue
            if _odd_tail(cells[0]) is not None:
                continue  # said by odd_names
            out.append(_field(cells, direction, line, lines))
            report.fields += 1
            report.names.append(out[-1].name)
        if reports is not None:
            reports.append(report)
    return out


#: "48 general purpose integer registers", "64 general-purpose bits": how many a family holds
_COUNT = re.compile(r"\b(\d+)\s+(?:general[- ]purpose\s+)?(?:\w+\s+)?(?:registers|bits)\b", re.I)

_VERSION_TOKEN = (
    rf"(\[\s*\d+\s*(\.\.|[-{DASHES}])\s*\d+\s*\]|\d+\.\d+(\.\d+)*|/|,|;|[{DASHES}]|and|cb3|e-series"
    r"|polyscope[- ]x|sw)"
)
_VERSIONISH = re.compile(rf"\s*({_VERSION_TOKEN}\s*)*", re.I)


def is_version_text(text: str) -> bool:
    """Whether a cell holds versions only ("5.23.0 / 10.11.0", "[24..47] 5.3.0"): a version cell."""
    return bool(re.search(r"\d", text)) and bool(_VERSIONISH.fullmatch(text))


def _version_start(cells: list[str]) -> int:
    """Where the version cells begin: the trailing cells that hold only versions (a comment of
    several paragraphs comes as several cells in the text forms); at least after the comment."""
    split = len(cells)
    while split > 3 and _VERSIONISH.fullmatch(cells[split - 1]):
        split -= 1
    return max(split, min(len(cells), 3))


def _field(cells: list[str], direction: str, line: int, lines: Lines) -> DocField:
    name, span, family = parse_name(cells[0])
    split = _version_start(cells)
    comment = " ".join(c.strip() for c in cells[2:split] if c.strip())
    version = " ".join(c.strip() for c in cells[split:] if c.strip())
    notes, rest = parse_versions(version, lines) if version else ([], "")
    if not version and comment:
        # an earlier edition merged the columns, or a cell is missing (e-Series safety_status)
        notes, comment = versions_in_text(comment, lines)
    if family and span is None:
        spans = spans_in(comment)
        span = (min(a for a, _ in spans), max(b for _, b in spans)) if spans else None
        counted = _COUNT.search(comment)
        if span is not None and counted is not None and span[1] - span[0] + 1 != int(counted.group(1)):
            # "48 integer registers ([24..47] available to external RTDE clients)": the comment
            # names one range of the family, not the family's; its range is not read from it
            span = None
    doc = comment if not rest else f"{comment} ({rest})"
    return DocField(
        name=name,
        direction=direction,
        type=lines.type_name(cells[1]),
        doc=doc,
        line=line,
        index=span if family else None,
        notes=notes,
        version_text=version,
    )


#: what may follow a name in its cell and is no part of it: a footnote mark (`[^1]`, `¹`, `*`, `†`)
_NAME_TAIL = re.compile(
    r"[\s*`]*(?:\[\^?[\w-]+\]|[\u00b9\u00b2\u00b3\u2070-\u2079]+|[*\u2020\u2021]+)?[\s*`]*"
)


def _odd_tail(cell: str) -> str | None:
    """What follows the name in a name cell when it is more than a footnote mark, else None."""
    text = name_text(cell)
    name, _, family = parse_name(cell)
    tail = "" if family else text[len(name) :] if text.startswith(name) else text
    return None if _NAME_TAIL.fullmatch(tail) else tail.strip()


def odd_names(tables: list[Table]) -> list[str]:
    """Name cells holding more than a name and a footnote mark (`name#hash`, `weird name: here`):
    their first word may not be the field's name; said with cell and line, the row not read."""
    return [
        f"line {line}: the name cell {cells[0].strip()[:60]!r} holds more than a name "
        f"({tail[:30]!r} after {parse_name(cells[0])[0]!r}): not read"
        for table in tables
        if table.is_field_table and table.direction is not None
        for line, cells in table.rows
        if len(cells) >= 2
        and cells[0].strip()
        and not is_placeholder(cells[0])
        and (tail := _odd_tail(cells[0])) is not None
    ]


def main_line(fields: list[DocField], default: str) -> str:
    """The product line a document speaks for: the one its version cells name first most often."""
    counts: Counter[str] = Counter()
    for fld in fields:
        for note in fld.notes:
            if note.versions:
                counts[next(iter(note.versions))] += 1
    return counts.most_common(1)[0][0] if counts else default


def merged_rows(fields: list[DocField], lines: Lines) -> list[str]:
    """Comment cells holding a further row (`… target_current VECTOR6D Target joint currents`): a
    copy that lost its columns (tabs expanded to spaces) ran rows together, and the versions read
    are another row's; said as a problem, so --write refuses the copy."""
    types = "|".join(
        sorted({re.escape(t) for t in lines.types.values() if t.isupper()}, key=len, reverse=True)
    )
    row = re.compile(rf"\b[A-Za-z]\w*_\w+\s+(?:{types})\b")
    return [
        f"line {f.line}: the comment of {f.name} holds another row ({m.group(0)!r}): rows run together, "
        "not one of the document's rows"
        for f in fields
        if (m := row.search(f.doc))
    ]
