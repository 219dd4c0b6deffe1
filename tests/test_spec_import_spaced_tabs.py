"""spec import on a tab copy whose tabs were turned into spaces: refused with what happened.

`expandtabs(8)` leaves one space where a cell ended a character before a tab stop
("Comment Introduced in version"), so no reader can say where a comment ends; before, the copy
gave "no field read" (tabs at 8, tab → 4 spaces) or rows run together (tabs at 4).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_page_footers import tabbed
from tests.test_spec_import_realworld import ESERIES, ROOT, _cli, rows, seed, spec

__all__ = ["rows", "seed", "spec"]  # the module fixtures, shared

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")

EXPANDED = {
    "tab stops at 8": lambda t: "\n".join(line.expandtabs(8) for line in t.split("\n")),
    "tab stops at 4": lambda t: "\n".join(line.expandtabs(4) for line in t.split("\n")),
    "tab → 4 spaces": lambda t: t.replace("\t", "    "),
}


@pytest.mark.parametrize("how", sorted(EXPANDED))
def test_tabs_turned_into_spaces_are_refused(tmp_path: Path, rows: dict, how: str) -> None:
    text = EXPANDED[how](tabbed(rows))
    assert "\t" not in text
    (tmp_path / "copy.txt").write_text(text, encoding="utf-8")
    run = _cli(tmp_path / "copy.txt", "--spec", ROOT / "spec")
    assert run.returncode == 2, run.stdout
    head = text.split("\n").index(next(line for line in text.split("\n") if line.startswith("Name ")))
    assert f"copy.txt: line {head + 1}: the field table's cells are apart by spaces" in run.stderr
    assert "tabs were turned into spaces" in run.stderr and "Traceback" not in run.stderr


def test_a_pdftotext_layout_copy_is_still_read(spec: Spec) -> None:
    """pdftotext -layout's columns line up under the header's: not taken for expanded tabs."""
    doc = read_document(ROOT / "tests" / "data" / "import" / "pdf_layout.txt", spec)
    assert doc.format == "columns-text" and doc.fields
