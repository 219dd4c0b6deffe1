"""The field tables of the text forms: tabs, `|`-ended cells, a cell per line, pdftotext's columns.

Each form has its reader; here they are chosen, their cells grouped into rows where a row starts
(a name cell followed by a type cell), and a table the copy stops inside is marked cut (`cut`).
"""

from __future__ import annotations

import re

from rtde_spec.importers import cb3_text, columns_text, eseries_text, rendered_text
from rtde_spec.importers.cells import Lines, parse_name
from rtde_spec.importers.cut import mark_cut
from rtde_spec.importers.model import Document
from rtde_spec.importers.spaced_tabs import refuse_expanded_tabs
from rtde_spec.importers.tables import Table
from rtde_spec.importers.wrapped import known_names
from rtde_spec.metamodel.schema import Spec


def read_text_tables(kind: str, text: str, doc: Document, lines: Lines, spec: Spec) -> list[Table]:
    """The tables of a text form (`kind`), rows grouped; what cannot be read goes to doc.problems."""

    def is_type(cell: str) -> bool:
        return cell.strip() != "" and lines.type_name(cell) in lines.types.values()

    def starts_row(name: str, type_: str) -> bool:
        word, _, _ = parse_name(name)
        return bool(re.fullmatch(r"[A-Za-z_][A-Za-z0-9_{}]*", word)) and is_type(type_)

    known = known_names(spec)
    if kind in ("cb3-text", "tab-text"):
        tables = cb3_text.read_tables(text, notes=doc.remarks)
    elif kind == "columns-text":
        refuse_expanded_tabs(text, is_type, doc.path)
        tables = columns_text.read_tables(text, is_type, known, doc.problems)
    else:
        read = (
            rendered_text.read_tables(text, starts_row, known, doc.problems, doc.remarks)
            if kind == "rendered-text"
            else eseries_text.read_tables(text, notes=doc.remarks)
        )
        tables = [eseries_text.split_rows(t, starts_row) for t in read]
        if kind == "e-series-text":  # every cell ends in `|`: one that starts no row is a row lost
            doc.problems += [
                _stray(t) for t in tables if t.is_field_table and any(c.strip() for _, c in t.stray)
            ]
    mark_cut(tables, doc.problems)
    # a header with no row under it and the text going on (repeated above a page's last lines)
    return [t for t in tables if t.rows or t.cut or not t.is_field_table]


def _stray(table: Table) -> str:
    cells = [(n, c) for n, c in table.stray if c.strip()]
    return (
        f"line {cells[0][0]}: {cells[0][1][:60]!r} and {len(cells) - 1} more cells of the table "
        f"{table.heading!r} start no row (no name cell followed by a type cell): not read"
    )
