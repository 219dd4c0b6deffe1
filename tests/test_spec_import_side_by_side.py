"""spec import on a tab copy of two field tables laid side by side (a page in two columns).

Each line holds a row of both tables; read as one table, the right table's cells became the
left rows' comments and versions (inputs "changed" to outputs, outputs "removed"), or nothing
was read when the headings shared a line. The repeated header cells say it: the halves are read
as the tables they are, or as one table in two columns under one heading.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_cut_pages import _fields
from tests.test_spec_import_page_footers import TAB_HEADER, TITLE, tabbed
from tests.test_spec_import_realworld import ESERIES, _read, rows, seed, spec

__all__ = ["rows", "seed", "spec"]  # the module fixtures, shared

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")


def _side(left: list[list[str]], right: list[list[str]]) -> list[str]:
    def cells(row: list[str]) -> list[str]:
        return (row + [""] * 4)[:4]

    blank = [[""] * 4] * abs(len(left) - len(right))
    left, right = (left, right + blank) if len(left) > len(right) else (left + blank, right)
    return ["\t".join(cells(a) + cells(b)) for a, b in zip(left, right, strict=True)]


HEADINGS = {
    "tab between": ["Robot Controller Inputs\tRobot Controller Outputs"],
    "spaces between": ["Robot Controller Inputs          Robot Controller Outputs"],
    "two lines": ["Robot Controller Inputs", "Robot Controller Outputs"],
}


@pytest.mark.parametrize("headings", sorted(HEADINGS))
def test_two_tables_side_by_side(tmp_path: Path, rows: dict, spec: Spec, headings: str) -> None:
    text = "\n".join(
        [TITLE, *HEADINGS[headings], f"{TAB_HEADER}\t{TAB_HEADER}", *_side(rows["input"], rows["output"])]
    )
    plain = _read(tmp_path, "plain.txt", tabbed(rows), spec)
    doc = _read(tmp_path, "side.txt", text + "\n", spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []


def test_one_table_in_two_columns(tmp_path: Path, rows: dict, spec: Spec) -> None:
    outputs = rows["output"]
    half = (len(outputs) + 1) // 2
    inputs = [TITLE, "Robot Controller Inputs", TAB_HEADER, *("\t".join(r) for r in rows["input"])]
    columns = [
        "Robot Controller Outputs",
        f"{TAB_HEADER}\t{TAB_HEADER}",
        *_side(outputs[:half], outputs[half:]),
    ]
    text = "\n".join([*inputs, *columns])
    plain = _read(tmp_path, "plain.txt", tabbed(rows), spec)
    doc = _read(tmp_path, "columns.txt", text + "\n", spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []


def test_html_tables_side_by_side_are_said_and_not_written(tmp_path: Path, rows: dict, spec: Spec) -> None:
    """An HTML page with the two tables as one (header cells repeated): the right half's cells were
    the left rows' comments (83 fields removed, nothing said). Now both halves' rows are read and
    the guess of the left half's direction is a problem, so --write holds."""
    head = "".join(f"<th>{h}</th>" for h in TAB_HEADER.split("\t") * 2)
    body = "".join(
        "<tr>" + "".join(f"<td>{c}</td>" for c in line.split("\t")) + "</tr>"
        for line in _side(rows["input"], rows["output"])
    )
    page = (
        f"<html><body><h1>{TITLE}</h1><h2>Robot Controller Inputs</h2><h2>Robot Controller Outputs</h2>"
        f"<table><tr>{head}</tr>{body}</table></body></html>"
    )
    doc = _read(tmp_path, "side.html", page, spec)
    names = [r[0] for r in rows["input"] + rows["output"]]
    assert sorted(f.name.replace("{X}", "X") for f in doc.fields) == sorted(names)
    assert any("holds two tables side by side" in p for p in doc.problems)
