"""spec import on the files people have besides text: UR's PDFs as downloaded, an Excel 97-2003
copy, a workbook saved under another name, text in UTF-16 without a byte-order mark or in UTF-32.
Each is read or named with what to do, never "cannot tell the document's form" or a traceback."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.test_spec_import_safety import _cli as run_cli

ROOT = Path(__file__).resolve().parent.parent
SPEC = str(ROOT / "spec")
PDF = b"%PDF-1.7\n%\xe2\xe3\xcf\xd3\n1 0 obj\n<< /Type /Catalog >>\nendobj\n"
GUIDE = """# RTDE guide (a copy)

## Robot Controller Outputs

| Name | Type | Comment | Introduced in version |
|---|---|---|---|
| timestamp | DOUBLE | Time elapsed since the controller was started [s] | |
| actual_q | VECTOR6D | Actual joint positions | |
| … and more fields … | | | |
"""


def _cli(path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return run_cli("spec", "import", str(path), "--spec-dir", SPEC, *args)


@pytest.mark.parametrize("codec", ["utf-16-le", "utf-16-be", "utf-32"])
def test_utf16_without_a_bom_and_utf32_are_read(tmp_path: Path, codec: str) -> None:
    """UTF-32's BOM (FF FE 00 00) begins with UTF-16 LE's; UTF-16 without one read as UTF-8 is NUL-spaced."""
    path = tmp_path / "guide.md"
    path.write_bytes(GUIDE.replace("\n", "\r\n").encode(codec))
    result = _cli(path)
    assert result.returncode == 0, result.stderr
    assert "0 added, 0 removed, 0 changed" in result.stdout


BINARY = {
    "pdf": (PDF, "a PDF; import its text: `pdftotext"),
    "xls": (bytes.fromhex("D0CF11E0A1B11AE1") + bytes(600), "an Excel 97-2003 (.xls)"),
    "binary": (b"Name\x00\x01\x02\x00\xff\x00\x00\x00\x10binary", "binary data (a NUL byte at offset 4)"),
}


@pytest.mark.parametrize("kind", list(BINARY))
@pytest.mark.parametrize(
    "form", [[], ["--form", "xlsx"], ["--form", "markdown"]], ids=["detected", "xlsx", "md"]
)
def test_a_pdf_or_an_old_xls_is_named(tmp_path: Path, kind: str, form: list) -> None:
    head, said = BINARY[kind]
    path = tmp_path / "Client_Interface.xls"
    path.write_bytes(head)
    result = _cli(path, *form)
    assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    if "NUL" in said and form == ["--form", "xlsx"]:  # read as a workbook: no ZIP
        assert "not a readable .xlsx workbook" in result.stderr
    else:
        assert said in result.stderr and str(path) in result.stderr, result.stderr


def test_a_workbook_under_another_name_is_read_as_one(tmp_path: Path) -> None:
    """A browser saves Client_Interface.xlsx as Client_Interface.xls or .xlsx.download; openpyxl refused
    those names (InvalidFileException, a traceback with --form xlsx)."""
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    sheet = book.active
    sheet.append(["Robot Controller Outputs"])
    sheet.append(["Name", "Type", "Comment", "Introduced in version"])
    sheet.append(["actual_q", "VECTOR6D", "Actual joint positions", None])
    sheet.append(["actual_tcp_jerk", "VECTOR6D", "Actual TCP jerk", "5.30.0"])
    sheet.append(["… and more", None, None, None])
    for name, form in (("Client_Interface.xls", []), ("Client_Interface.xlsx.download", ["--form", "xlsx"])):
        path = tmp_path / name
        book.save(path)
        result = _cli(path, "--json", *form)
        assert result.returncode == 0 and '"actual_tcp_jerk"' in result.stdout, result.stderr


def test_a_form_feed_page_break_in_a_tab_copy_goes_on_with_the_table(tmp_path: Path) -> None:
    """pdftotext ends a page with a form feed: the tab reader's splitlines() took it for a blank line,
    so the rows after the page's running title became a table of no direction, not read."""
    from rtde_spec.importers import read_document
    from rtde_spec.metamodel.loader import load_spec

    head = "Name\tType\tComment\tIntroduced in version"
    names = ["timestamp", "target_q", "target_qd", "actual_q", "actual_qd"]
    types = ["DOUBLE", "VECTOR6D", "VECTOR6D", "VECTOR6D", "VECTOR6D"]
    rows = [f"{n}\t{t}\tsome words\t" for n, t in zip(names, types, strict=True)]
    title = "Real-Time Data Exchange (RTDE) Guide"
    lines = [title, "Robot Controller Outputs", head, *rows[:3], "\f" + title, head, *rows[3:]]
    lines.append("… and more")
    path = tmp_path / "copied.txt"
    path.write_text("\n".join(lines) + "\n")
    doc = read_document(path, load_spec(ROOT / "spec"))
    assert [(f.name, f.direction) for f in doc.fields] == [(n, "output") for n in names]
    assert not doc.problems


def test_lone_cr_line_ends_are_line_ends(tmp_path: Path) -> None:
    """Excel for Mac's tab-delimited text ends lines with CR alone: one long line, no form found."""
    path = tmp_path / "guide.md"
    path.write_bytes(GUIDE.replace("\n", "\r").encode())
    result = _cli(path)
    assert result.returncode == 0 and "0 added, 0 removed, 0 changed" in result.stdout, result.stderr


def test_markdown_rows_without_the_outer_pipes(tmp_path: Path) -> None:
    """GFM tables may leave out the leading and trailing pipes (`Name | Type | Comment`)."""
    bare = "\n".join(
        line.strip().strip("|").strip() if line.startswith("|") else line for line in GUIDE.splitlines()
    )
    assert "\n| " not in bare
    path = tmp_path / "guide.md"
    path.write_text(bare + "\n")
    result = _cli(path, "--json")
    assert result.returncode == 0, result.stderr
    assert '"fields": 2' in result.stdout and '"removed": []' in result.stdout, result.stdout


def test_html_whose_section_titles_are_paragraphs(tmp_path: Path) -> None:
    """A page from a CMS or a word processor titles its tables with <p><strong>, not <h3>: both
    tables were 'of no direction' and the import ended in 'no field read'."""
    head = "<tr><th>Name</th><th>Type</th><th>Comment</th><th>Introduced in version</th></tr>"
    page = (
        "<html><body><h2>Field names and associated types</h2>"
        "<p><strong>Robot Controller Inputs</strong></p><table>" + head + "<tr><td>speed_slider_fraction</td>"
        "<td>DOUBLE</td><td>New speed slider value</td><td></td></tr><tr><td>… and more</td></tr></table>"
        "<p><strong>Robot Controller Outputs</strong></p><p>The client should subscribe to one output.</p>"
        "<table>"
        + head
        + "<tr><td>actual_q</td><td>VECTOR6D</td><td>Actual joint positions</td><td></td></tr>"
        "<tr><td>… and more</td></tr></table><table>" + head + "<tr><td>actual_qd</td><td>VECTOR6D</td>"
        "<td>Actual joint velocities</td><td></td></tr></table></body></html>"
    )
    path = tmp_path / "guide.html"
    path.write_text(page)
    from rtde_spec.importers import read_document
    from rtde_spec.metamodel.loader import load_spec

    doc = read_document(path, load_spec(ROOT / "spec"))
    assert [(f.name, f.direction) for f in doc.fields] == [
        ("speed_slider_fraction", "input"),
        ("actual_q", "output"),
    ]
    # the third table has no title of its own: never the one the second table used
    assert len(doc.problems) == 1 and "names no direction" in doc.problems[0], doc.problems


def test_no_field_read_says_which_table_had_no_direction(tmp_path: Path) -> None:
    """'no field read (1 other tables seen)' named neither the table nor why it was not read."""
    path = tmp_path / "fields.md"
    path.write_text(
        "# Fields\n\n| Name | Type | Comment |\n|---|---|---|\n| actual_q | VECTOR6D | Actual joint q |\n"
    )
    result = _cli(path)
    assert result.returncode == 2 and "no field read" in result.stderr
    assert "the field table at line 3 (1 rows, heading 'Fields') names no direction" in result.stderr, (
        result.stderr
    )


def test_a_browser_print_footer_on_one_line_is_no_part_of_a_row(tmp_path: Path) -> None:
    """A page printed from a browser has its address and "1/2" in one footer line; pdftotext -layout
    keeps them on one line, which went into the comment of the page's last row (and --write would
    put the address into the spec's doc)."""
    from rtde_spec.importers import read_document
    from rtde_spec.metamodel.loader import load_spec

    cols = "{:<26}{:<10}{:<44}{}"
    rows = [
        ("timestamp", "DOUBLE", "Time elapsed since the controller was started", ""),
        ("target_q", "VECTOR6D", "Target joint positions", ""),
    ]
    head = cols.format("Name", "Type", "Comment", "Introduced in version")
    title = "Real-Time Data Exchange (RTDE) Guide"
    footer = "https://docs.example.invalid/rtde-guide.html" + " " * 30 + "1/2"
    lines = [title, "", "Robot Controller Outputs", "", head, "", cols.format(*rows[0]), footer]
    lines += ["\f" + title, "", head, "", cols.format(*rows[1]), "", "… and more"]
    path = tmp_path / "printed.txt"
    path.write_text("\n".join(lines) + "\n")
    doc = read_document(path, load_spec(ROOT / "spec"))
    assert doc.format == "columns-text"
    assert [(f.name, f.doc) for f in doc.fields] == [(n, c) for n, _, c, _ in rows]


def test_a_paragraph_title_never_renames_a_primary_table() -> None:
    """A primary message table is named by its heading (the member's title); a short <p> between
    them that names a direction ("Tool outputs") stays text."""
    from rtde_spec.importers.html_doc import read_tables

    page = (
        "<h3>Tool Data (Sub Package of Robot State Message)</h3><p>Tool outputs</p>"
        "<table><tr><th>Field</th><th>Description</th></tr>"
        "<tr><td>double analogInput0</td><td></td></tr></table>"
    )
    assert [t.heading for t in read_tables(page)] == ["Tool Data (Sub Package of Robot State Message)"]
