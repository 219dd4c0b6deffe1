"""spec import reads ClientInterfaces_Realtime.pdf as pdftotext gives it, plain and -layout.

The plain text prints cells as paragraphs out of the table's order: a Notes column's link to
a chapter ("Safety Mode Types") stands where the next (unnamed) row's name would be, a row's
name cell comes after the page's last row (before its page mark), the TOTAL label after its
two numbers. `-layout` keeps columns but wraps a cell over the lines below its row (the name
"Tool vector" / "actual", a note's link) and splits the header over two lines. The documents
here are written by these tests in those shapes, from the spec's own message for 5.9 and 5.10,
with the one real difference of UR's document: three unnamed 1-double rows where the spec has
reserved_5 as double[3] (a recorded conflict of the real-time guide).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import detect_format, read_document
from rtde_spec.importers.realtime_diff import diff_realtime
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.realtime import load_realtime
from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_realtime import ROOT, Row, spec, table_rows

__all__ = ["spec"]  # the module fixture, shared

CONTENTS = ["Contents", "1. Introduction", "5. Safety Mode Types", "6. Safety Status Types",
            "7. Control Modes", "8. Robot Modes", "9. Joint Modes"]  # fmt: skip
LINKS = {"Robot mode": "Robot Modes", "Joint modes": "Control Modes", "Safety mode": "Safety Mode Types"}
DISPLACED = "Tool accelerometer values"  # pdftotext prints this name after the page's last row


def pdf_rows(spec: Spec, edition: str) -> list[Row]:
    """The spec's message for `edition` as the PDF lists it: reserved_5 as three 1-double rows."""
    rows = table_rows(spec, "e-series", edition)
    at = next(i for i, r in enumerate(rows) if r[5].startswith("Unused: used by Universal Robots"))
    first = int(rows[at][4].split("-")[0])
    three = [
        ["", "double", "1", "8", str(first + k), "Used by Universal Robots software only"] for k in range(3)
    ]
    return [*rows[:at], *three, *rows[at + 1 :]]


def plain(title: str, rows: list[Row]) -> str:
    """pdftotext without -layout: a paragraph per cell, in the order the PDF draws them."""
    paras = [*CONTENTS, f"Chapter 2\n{title}\n(deprecated since version 3.5)\nMeaning", "Type",
             "Number of\nvalues", "Size in\nbytes", "Gnuplot\ncol.", "Notes"]  # fmt: skip
    displaced, page_after = "", ""
    for row in rows:
        if row[0] == "TOTAL":  # its numbers first
            paras += [row[1], row[2], "TOTAL", "Safety Status Types", "If less than that is received ..."]
            break
        name, type_, count, size, column, notes = row
        if name == "Message Size":
            paras += [name, type_, count, size]  # its note is drawn elsewhere
            continue
        if name == DISPLACED:
            displaced, name = name, ""
        if name == "Linear momentum norm":
            page_after = "next"
        cell = name.replace(" ", "\n", 1) if len(name) > 14 else name
        cells = [cell, type_, count, size, column, notes]
        if page_after == "here":
            cells[0 if name else 1] = "Chapter 2\n" + cells[0 if name else 1]
            page_after = ""
        paras += [c for c in cells if c]
        if name in LINKS:
            paras.append(LINKS[name])
        if page_after == "next" and not name:
            paras += [displaced.replace(" ", "\n"), "-3-"]
            page_after = "here"
    return "\n\n".join(paras) + "\n"


def layout(title: str, rows: list[Row]) -> str:
    """pdftotext -layout: columns of spaces; a wrapped cell goes on under its row."""
    widths = (17, 10, 13, 10, 13)
    out = [*CONTENTS, "", f" {title}", " (deprecated since version 3.5)", "",
           "  Meaning          Type      Number of   Size in   Gnuplot    Notes",
           "                             values      bytes     col."]  # fmt: skip
    for k, row in enumerate(rows):
        if row[0] == "TOTAL":
            out.append(f"  {'TOTAL':<{widths[0] + widths[1]}}{row[1]:<{widths[2]}}{row[2]}")
            break
        name, type_, count, size, column, notes = row
        if k == len(rows) // 2:  # a page break: other column widths on the next page
            out += ["", "", f"{'-3-':>55}", "Chapter 2", ""]
            widths = (16, 9, 4, 5, 12)
        words = name.split()
        fit = max([1, *(n for n in range(len(words) + 1) if len(" ".join(words[:n])) <= widths[0] - 2)])
        first, rest = " ".join(words[:fit]), " ".join(words[fit:])
        note, more = (notes[:40], notes[40:]) if len(notes) > 40 else (notes, "")
        cells = [first, type_, count, size, column]
        out.append("  " + "".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)) + note)
        below = [m for m in (more.strip(), LINKS.get(name, "")) if m]
        for line in range(max(len(rest.split()), len(below))):  # a word of the name a line, as the PDF
            word = rest.split()[line] if line < len(rest.split()) else ""
            out.append("  " + word.ljust(sum(widths)) + (below[line] if line < len(below) else ""))
    return "\n".join(out) + "\n\n If less than that is received ...\n"


@pytest.mark.parametrize("form", [plain, layout])
@pytest.mark.parametrize("edition", ["5.9.0", "5.10.0"])
def test_the_pdf_text_reads_every_row_and_leaves_only_the_recorded_conflict(
    spec: Spec, tmp_path: Path, form: object, edition: str
) -> None:
    rows = pdf_rows(spec, edition)
    title = f"2. RealTime {edition.removesuffix('.0')}"
    path = tmp_path / "realtime.txt"
    path.write_text(form(title, rows))  # type: ignore[operator]
    assert detect_format(path.read_text()) == "rendered-text"
    doc = read_document(path, spec)
    [table] = doc.realtime
    assert (table.edition, table.total) == (edition, (int(rows[-1][1]), int(rows[-1][2])))
    assert [r.key for r in table.rows] == [r[0].lower().replace(" ", "_") for r in rows[1:-1]]
    assert [r.key for r in table.header] == ["message_size"]
    assert not any("stands where" in r or "add up" in r for r in doc.remarks), doc.remarks
    realtime, catalogue = load_realtime(ROOT / "spec"), Catalogue(spec)
    changes = diff_realtime(doc, realtime, catalogue)
    assert all(c.known is not None for c in changes), [c.record() for c in changes if c.known is None]
    assert sorted((c.field, c.what) for c in changes) == [
        ("(unnamed) after reserved_5", "added"),
        ("(unnamed) after reserved_5", "added"),
        ("reserved_5", "type"),
    ]
    other = read_document(path, spec, source="someone-elses-table")  # the conflict is the guide's only
    assert all(c.known is None for c in diff_realtime(other, realtime, catalogue))
