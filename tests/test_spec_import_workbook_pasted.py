"""spec import on a workbook holding the CB3 guide's text pasted into a sheet.

The guide's text has a blank line between some rows of a table (input_double_register_X, then a
blank, then external_force_torque); pasted, each is a blank row, which ended the table: every row
after it was dropped and its field "removed" with nothing said (64 of the guide's 89).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import Spec

ROOT = Path(__file__).resolve().parent.parent
CB3 = ROOT.parent / "shared" / "seeds" / "rtde-guide-cb3-era.txt"

pytestmark = pytest.mark.skipif(not CB3.is_file(), reason="the shared seeds are not beside this checkout")


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _fields(path: Path, spec: Spec) -> list[tuple]:
    doc = read_document(path, spec, source="cb3-guide")
    return [(f.name, f.direction, f.type, f.doc, f.notes, f.index) for f in doc.fields]


def test_the_cb3_guide_pasted_into_a_sheet_reads_as_its_text(tmp_path: Path, spec: Spec) -> None:
    openpyxl = pytest.importorskip("openpyxl")
    text = CB3.read_text(encoding="utf-8")
    assert "\n\nexternal_force_torque\t" in text  # the blank line inside the inputs table
    book = openpyxl.Workbook()
    sheet = book.active
    for line in text.split("\n"):
        sheet.append(line.split("\t"))
    path = tmp_path / "guide.xlsx"
    book.save(path)
    assert _fields(path, spec) == _fields(CB3, spec)
