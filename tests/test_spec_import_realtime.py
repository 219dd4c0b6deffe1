"""spec import reads the real-time interface's tables (port 30003) in every form UR's copies take.

The small documents in tests/data/import are written for these tests in the shapes of the
real copies (the docs site's page as a browser renders it, the manual converted to pipes
without a ruler, the client-interface workbook's sheets); the complete tables are built
here from the spec itself, so a clean re-import and exactly the hand-made changes prove
the reader and the diff, not a copy of UR's text.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.importers import detect_format, read_document
from rtde_spec.importers.realtime_diff import plan_for
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.realtime import PRIMITIVES, load_realtime
from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_forms import _cli

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(__file__).parent / "data" / "import"

Row = list[str]


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _json(*args: str) -> dict[str, Any]:
    result = _cli(*args, "--spec-dir", str(ROOT / "spec"), "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)  # type: ignore[no-any-return]


def table_rows(spec: Spec, line: str, edition: str) -> list[Row]:
    """The message the spec gives `edition` as UR's table rows: unnamed reserved rows, TOTAL."""
    fields = plan_for(load_realtime(ROOT / "spec"), Catalogue(spec), line, edition)
    rows: list[Row] = [["Message Size", "integer", "1", "4", "", "Total message length in bytes"]]
    column, size = 1, 4
    for f in fields:
        count = f.count or 1
        name = "" if f.name.startswith("reserved") else f.name.replace("_", " ").capitalize()
        span = str(column) if count == 1 else f"{column} - {column + count - 1}"
        rows.append([name, f.type, str(count), str(count * PRIMITIVES[f.type][1]), span, f.doc or ""])
        column += count
        size += count * PRIMITIVES[f.type][1]
    rows.append(["TOTAL", str(column - 1), str(size), f"{column - 1} values in a {size} byte package"])
    return rows


HEAD = ["Meaning", "Type", "Number of values", "Size in bytes", "Gnuplot col.", "Notes"]


def rendered(title: str, rows: list[Row]) -> str:
    """The docs site's page as copied from a browser: a paragraph per cell."""
    cells = [c for row in [HEAD, *rows] for c in row if c]
    return f"e-Series (500 Hz):\n\n{title}\n\n" + "\n\n".join(cells) + "\n"


def markdown(title: str, rows: list[Row]) -> str:
    """The manual's page converted to pipes: no ruler, trailing empty columns."""
    lines = [f"| {' | '.join(r)} | |||" for r in [HEAD, *rows]]
    return f"{title}\n(deprecated since version 3.5)\n" + "\n".join(lines) + "\n"


def spaced(title: str, rows: list[Row]) -> str:
    """The manual's page as a text extractor gives it: a row per line, spaces between cells."""
    lines = [" ".join(c for c in r if c) for r in [HEAD, *rows]]
    return f"{title}\n\n(deprecated since version 3.5)\n\n" + "\n".join(lines) + "\n"


def html(title: str, rows: list[Row]) -> str:
    cells = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    head = "<tr>" + "".join(f"<th>{c}</th>" for c in HEAD) + "</tr>"
    return f"<html><body><h2>{title}</h2><table>{head}{cells}</table></body></html>"


def test_the_rendered_page_is_detected_and_a_table_that_stops_early_removes_nothing() -> None:
    text = (DATA / "realtime_rendered.txt").read_text(encoding="utf-8")
    assert detect_format(text) == "rendered-text"
    out = _json(str(DATA / "realtime_rendered.txt"))
    assert out["interfaces"] == ["realtime"] and (out["line"], out["edition"]) == ("e-series", "5.9.0")
    [table] = out["realtime"]
    assert (table["title"], table["rows"], table["total_bytes"]) == ("RealTime 5.9", 2, None)
    assert (table["spec_fields"], table["spec_bytes"]) == (39, 1140)
    assert out["removed"] == [] and out["changed"] == []
    assert any("no TOTAL row follows" in r and "37 spec fields" in r for r in out["remarks"])


def test_the_manual_in_pipes_without_a_ruler_and_a_placeholder_row() -> None:
    out = _json(str(DATA / "realtime_manual.md"))
    [table] = out["realtime"]
    assert (table["title"], table["edition"], table["rows"]) == ("RealTime 5.10", "5.10.0", 2)
    assert table["skipped"] == [{"line": 7, "cell": "… and more rows …"}]
    assert out["removed"] == [] and any("placeholder row" in r for r in out["remarks"])


@pytest.mark.parametrize(
    ("form", "suffix"), [(rendered, ".txt"), (markdown, ".md"), (html, ".html"), (spaced, ".text")]
)
def test_a_whole_table_built_from_the_spec_reimports_clean(
    spec: Spec, tmp_path: Path, form: Any, suffix: str
) -> None:
    path = tmp_path / f"realtime{suffix}"
    path.write_text(form("RealTime 5.10", table_rows(spec, "e-series", "5.10.0")), encoding="utf-8")
    out = _json(str(path))
    [table] = out["realtime"]
    assert (table["rows"], table["total_bytes"], table["spec_bytes"]) == (42, 1220, 1220)
    assert (out["added"], out["removed"], out["changed"]) == ([], [], [])


def test_exactly_the_hand_made_changes_are_reported(spec: Spec, tmp_path: Path) -> None:
    rows = table_rows(spec, "e-series", "5.10.0")
    names = [r[0] for r in rows]
    rows[names.index("Payload cog")][2:4] = ["2", "16"]  # a count changed
    rows.insert(names.index("Elbow position"), ["Future value", "double", "1", "8", "", "A new value"])
    rows.remove(rows[names.index("Speed scaling")])  # a row gone
    rows[-1][2] = "1212"  # the TOTAL the edited rows add up to
    path = tmp_path / "realtime.txt"
    path.write_text(rendered("RealTime 5.10", rows), encoding="utf-8")
    out = _json(str(path))
    assert [(c["field"], c["new"]) for c in out["added"]] == [("future_value", "double")]
    assert [(c["field"], c["old"]) for c in out["removed"]] == [("speed_scaling", "double")]
    changed = {(c["field"], c["what"], c["old"], c["new"]) for c in out["changed"]}
    assert changed == {("payload_cog", "type", "double[3]", "double[2]"), ("message", "length", 1220, 1212)}
    # an older edition's table of the same message: the 5.10 payload rows are newer than it
    older = tmp_path / "realtime59.txt"
    older.write_text(rendered("RealTime 5.9", table_rows(spec, "e-series", "5.9.0")), encoding="utf-8")
    assert (lambda o: (o["added"], o["removed"], o["changed"]))(_json(str(older))) == ([], [], [])


def test_a_row_the_spec_sends_only_later_is_an_availability_change(spec: Spec, tmp_path: Path) -> None:
    rows = table_rows(spec, "e-series", "5.10.0")
    path = tmp_path / "realtime.md"
    path.write_text(markdown("RealTime 5.9", rows), encoding="utf-8")  # 5.10's rows under a 5.9 title
    out = _json(str(path))
    moved = {c["field"]: c["new"] for c in out["changed"] if c["what"] == "availability"}
    assert moved == {n: {"e-series": "<= 5.9.0"} for n in ("payload_mass", "payload_cog", "payload_inertia")}


def _listing_sheet(book: Any, title: str) -> None:
    sheet = book.create_sheet(title)
    for line in [
        "Primary and secondary client",
        "int messageSize (total size including robot mode data, joint data, ...)",
        "unsigned char messageType = ROBOT_STATE = 16",
        "Joint data",
        "int packageSize",
        "unsigned char packageType = JOINT_DATA = 1",
        "for each joint:",
        "   double q_actual",
        "   double q_target",
        "double afterTheBlock",  # no "end": the indent ends the block
    ]:
        sheet.append([line])


def test_the_workbook_realtime_sheets_and_primary_listing_sheets(spec: Spec, tmp_path: Path) -> None:
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    index = book.active
    index.title = "Index"
    index.append(["The realtime (125 Hz) communications interface"])
    sheet = book.create_sheet("RealTime_3.2")
    sheet.append(["Return to Index"])
    spread = lambda r: [c for cell in r for c in (cell, None)]  # noqa: E731 - merged cells read empty
    sheet.append(spread(HEAD))
    for row in table_rows(spec, "cb3", "3.2.0"):
        sheet.append(spread(row))
    old = book.create_sheet("Pre-3.0")
    old.append(HEAD)
    old.append(["Time", "double", 1, 8, 1, "Time elapsed"])
    _listing_sheet(book, "5.4")
    _listing_sheet(book, "5.9")
    path = tmp_path / "Client_Interface.xlsx"
    book.save(path)
    doc = read_document(path, spec)
    assert doc.interfaces == ["primary", "realtime"]
    assert [(t.title, t.edition, t.product_line, len(t.rows)) for t in doc.realtime] == [
        ("RealTime_3.2", "3.2.0", "cb3", 35),
        ("Pre-3.0", None, None, 1),
    ]
    [joint] = doc.members
    assert [(f.name, f.group) for f in joint.fields] == [
        ("q_actual", "repeat 6"),
        ("q_target", "repeat 6"),
        ("afterTheBlock", ""),
    ]
    assert (doc.line, doc.edition) == ("e-series", "5.9.0")
    out = _json(str(path))
    assert [c for c in out["changed"] + out["removed"] if c["where"].startswith("realtime")] == []
    assert any("'Pre-3.0'" in r and "not compared" in r for r in out["remarks"])
    assert any("sheet '5.4'" in r and "older edition" in r for r in out["remarks"])


def test_write_leaves_the_realtime_spec_to_a_person(spec: Spec, tmp_path: Path) -> None:
    tree = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", tree)
    rows = table_rows(spec, "e-series", "5.10.0")
    rows.insert(3, ["Future value", "double", "1", "8", "", "A new value"])
    path = tmp_path / "realtime.txt"
    path.write_text(rendered("RealTime 5.10", rows), encoding="utf-8")
    before = (tree / "realtime" / "interface.yaml").read_bytes()
    result = _cli(str(path), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0, result.stderr
    assert "not written: 1 real-time changes" in result.stderr
    assert (tree / "realtime" / "interface.yaml").read_bytes() == before


def test_reserved_rows_may_carry_the_link_text_of_the_row_above(spec: Spec, tmp_path: Path) -> None:
    """A rendered copy puts the link under "Safety mode" ("Safety Mode Types") before the unnamed row."""
    rows = table_rows(spec, "e-series", "5.10.0")
    at = next(i for i, r in enumerate(rows) if r[0] == "Safety mode")
    rows[at] = [*rows[at], "Safety Mode Types"]
    path = tmp_path / "realtime.txt"
    path.write_text(rendered("RealTime 5.10", rows), encoding="utf-8")
    out = _json(str(path))
    assert (out["added"], out["removed"], out["changed"]) == ([], [], [])
    assert any("'Safety Mode Types' stands where the spec has reserved_1" in r for r in out["remarks"])


def test_a_hostile_realtime_page_is_refused_in_bounded_time(spec: Spec, tmp_path: Path) -> None:
    """Rows without end after a header: refused at the row limit, quickly, as a usage error."""
    import time

    from rtde_spec.errors import UsageError
    from rtde_spec.importers.cells import Lines
    from rtde_spec.importers.realtime_tables import read_paragraphs, read_spaced

    head = "RealTime 5.10\n\n" + "\n\n".join(HEAD) + "\n\n"
    start = time.perf_counter()
    with pytest.raises(UsageError, match="table rows"):
        read_paragraphs(head + "x\n\ndouble\n\n1\n\n8\n\n" * 30_000, Lines.of(spec))
    with pytest.raises(UsageError, match="table rows"):
        read_spaced(" ".join(HEAD) + "\n" + "x double 1 8 1 n\n" * 30_000, Lines.of(spec))
    assert time.perf_counter() - start < 20
    # headers alone, over and over: no quadratic rescans, nothing read
    many = ("RealTime 5.10\n\n" + "\n\n".join(HEAD) + "\n\n") * 20_000
    start = time.perf_counter()
    assert all(t.rows == [] for t in read_paragraphs(many, Lines.of(spec)))
    assert time.perf_counter() - start < 20


def test_two_tables_on_one_page_keep_their_titles_out_of_the_rows(spec: Spec, tmp_path: Path) -> None:
    """The docs site's page lists RealTime 5.9, then RealTime 5.10; a table without its TOTAL row
    runs up to the next title, which names the next table, not a note of the last row."""
    first = table_rows(spec, "e-series", "5.9.0")[:-1]  # no TOTAL row
    text = (
        rendered("RealTime 5.9", first)
        + "\n"
        + rendered("RealTime 5.10", table_rows(spec, "e-series", "5.10.0"))
    )
    path = tmp_path / "realtime.txt"
    path.write_text(text, encoding="utf-8")
    doc = read_document(path, spec)
    assert [(t.title, len(t.rows)) for t in doc.realtime] == [("RealTime 5.9", 39), ("RealTime 5.10", 42)]
    assert "RealTime 5.10" not in doc.realtime[0].rows[-1].doc
    out = _json(str(path))
    assert (out["added"], out["removed"], out["changed"]) == ([], [], [])
