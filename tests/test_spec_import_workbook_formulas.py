"""spec import on a workbook whose numbers are formulas saved without their values.

A workbook written by a tool that does not compute formulas (openpyxl, pandas, a script) keeps
`=SUM(D3:D40)` in the TOTAL row and no value; read with its values (data_only) the cell is empty.
The TOTAL was then not compared and nothing said so; a row whose size is such a formula was
dropped and its field looked removed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.importers.realtime_diff import diff_realtime
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.realtime import load_realtime
from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_realtime import HEAD, ROOT, spec, table_rows

__all__ = ["spec"]


def _book(tmp_path: Path, rows: list[list[str]]) -> Path:
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.title = "RealTime_3.2"
    sheet.append(HEAD)
    for row in rows:
        sheet.append([int(c) if c.isdigit() else c for c in row])
    path = tmp_path / "Client_Interface.xlsx"
    book.save(path)
    return path


def _changes(path: Path, spec: Spec) -> tuple[list, list[str]]:
    doc = read_document(path, spec)
    realtime = load_realtime(ROOT / "spec")
    changes = diff_realtime(doc, realtime, Catalogue(spec))
    return [c for c in changes if c.known is None], doc.remarks


def test_a_total_without_its_value_is_said_not_compared(tmp_path: Path, spec: Spec) -> None:
    rows = table_rows(spec, "cb3", "3.2.0")
    assert rows[-1][0] == "TOTAL"
    rows[-1][1:3] = [f"=SUM(C2:C{len(rows)})", f"=SUM(D2:D{len(rows)})"]
    new, remarks = _changes(_book(tmp_path, rows), spec)
    assert new == []
    line = len(rows) + 1
    assert any(f"line {line} ('TOTAL')" in r and "length is not compared" in r for r in remarks), remarks


def test_a_row_whose_size_is_a_formula_is_said_not_removed(tmp_path: Path, spec: Spec) -> None:
    rows = table_rows(spec, "cb3", "3.2.0")
    rows[3][3] = "=C5*8"
    new, remarks = _changes(_book(tmp_path, rows), spec)
    assert [c for c in new if c.kind == "removed"] == []
    assert any("line 5 (" in r and "without its numbers" in r for r in remarks), remarks
