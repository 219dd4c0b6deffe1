"""Markdown tables (`| a | b |` rows under a `|---|` ruler), headings from `#` lines.

A page converted to pipes without a ruler (UR's manual as some tools copy it) starts its
table at a row of known header cells: Name | Type | Comment, or Meaning | Type | Number of
values; a line of text that is no row (the title "RealTime 5.10") is the heading.
"""

from __future__ import annotations

import re

from rtde_spec.importers.tables import Table, check_rows

_KNOWN_HEADS = (("name", "type", "comment"), ("meaning", "type", "number of values"))
#: a footnote reference (`**timestamp**[^1]`): no part of the cell's text
_FOOTNOTE = re.compile(r"\[\^[^\]\s]*\]")
_RULER = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def _split(line: str) -> list[str]:
    text = line.strip()
    if text.startswith("|"):
        text = text[1:]
    if text.endswith("|") and not text.endswith("\\|"):
        text = text[:-1]
    cells = re.split(r"(?<!\\)\|", text)
    return [_FOOTNOTE.sub("", c).strip().replace("\\|", "|") for c in cells]


def read_tables(text: str) -> list[Table]:
    tables: list[Table] = []
    heading = title = ""
    lines = text.splitlines()
    current: Table | None = None
    count = 0
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if stripped.startswith("#"):
            heading = title = stripped.lstrip("#").strip()
            current = None
            continue
        nxt = lines[number] if number < len(lines) else ""
        # GFM rows may lack the outer pipes (`Name | Type`): a row in a table, or a header over a ruler
        bare = "|" in stripped and (current is not None or bool(_RULER.match(nxt.strip())))
        if not stripped.startswith("|") and not bare:
            current = None
            if 0 < len(stripped) <= 60 and not stripped.endswith(".") and not stripped.startswith("("):
                title = stripped  # a title line of a page converted without # headings
            continue
        if _RULER.match(stripped):
            continue
        cells = _split(stripped)
        known = tuple(c.lower().rstrip(".") for c in cells[:3]) in _KNOWN_HEADS
        if known and current is not None and not current.rows:
            continue  # a header repeated
        if (current is None and _RULER.match(nxt.strip())) or known:
            # a real-time table is named by its title line (RealTime 5.10); field tables by # headings
            realtime = tuple(c.lower() for c in cells[:3]) == _KNOWN_HEADS[1]
            current = Table(title if realtime else heading, cells, number)
            tables.append(current)
        elif current is not None:
            current.rows.append((number, _split(stripped)))
            count += 1
            check_rows(count, number)
    return tables
