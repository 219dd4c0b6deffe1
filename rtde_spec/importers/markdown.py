"""Markdown tables (`| a | b |` rows under a `|---|` ruler), headings from `#` lines."""

from __future__ import annotations

import re

from rtde_spec.importers.tables import Table, check_rows

_RULER = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def _split(line: str) -> list[str]:
    text = line.strip()
    if text.startswith("|"):
        text = text[1:]
    if text.endswith("|") and not text.endswith("\\|"):
        text = text[:-1]
    cells = re.split(r"(?<!\\)\|", text)
    return [c.strip().replace("\\|", "|") for c in cells]


def read_tables(text: str) -> list[Table]:
    tables: list[Table] = []
    heading = ""
    lines = text.splitlines()
    current: Table | None = None
    count = 0
    for number, line in enumerate(lines, start=1):
        stripped = line.strip()
        if stripped.startswith("#"):
            heading = stripped.lstrip("#").strip()
            current = None
            continue
        if not stripped.startswith("|"):
            current = None
            continue
        if _RULER.match(stripped):
            continue
        nxt = lines[number] if number < len(lines) else ""
        if current is None and _RULER.match(nxt.strip()):
            current = Table(heading, _split(stripped), number)
            tables.append(current)
        elif current is not None:
            current.rows.append((number, _split(stripped)))
            count += 1
            check_rows(count, number)
    return tables
