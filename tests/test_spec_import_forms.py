"""spec import reads every form a copy of UR's documents takes, and says what it read.

Each document here is a small one written for the test in the shape of a real copy
(the support article copied from a browser, a Markdown excerpt, the workbook, a page).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.errors import UsageError
from rtde_spec.importers import detect_format, read_document
from rtde_spec.importers.html_doc import read_tables
from rtde_spec.importers.tables import MAX_ROWS
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import Spec

ROOT = Path(__file__).resolve().parent.parent

# the support article as a browser renders it: every cell a paragraph, blank lines between
RENDERED = """Real-Time Data Exchange (RTDE) Guide

Robot Controller Inputs

Name

Type

Comment

Introduced in version

speed_slider_mask

UINT32

0 = don't change speed slider with this input
1 = use speed_slider_fraction to set speed slider value

speed_slider_fraction

DOUBLE

New speed slider value

brand_new_input

DOUBLE

A field of a future release

5.30.0

Robot Controller Outputs

Name

Type

Comment

Introduced in version

timestamp

DOUBLE

Time elapsed since the controller was started [s]

actual_q

VECTOR6D

Actual joint positions

payload

DOUBLE

Payload mass Kg

3.11.0 / 5.0.0
"""


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "rtde_spec.cli", "spec", "import", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )


def _json(*args: str) -> dict[str, Any]:
    result = _cli(*args, "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)  # type: ignore[no-any-return]


def test_rendered_text_is_detected_and_read_row_by_row(spec: Spec, tmp_path: Path) -> None:
    path = tmp_path / "rtde-guide.txt"
    path.write_text(RENDERED)
    assert detect_format(RENDERED) == "rendered-text"
    doc = read_document(path, spec)
    rows = [(f.direction, f.name, f.type, f.version_text) for f in doc.fields]
    assert rows == [
        ("input", "speed_slider_mask", "UINT32", ""),
        ("input", "speed_slider_fraction", "DOUBLE", ""),
        ("input", "brand_new_input", "DOUBLE", "5.30.0"),
        ("output", "timestamp", "DOUBLE", ""),
        ("output", "actual_q", "VECTOR6D", ""),
        ("output", "payload", "DOUBLE", "3.11.0 / 5.0.0"),
    ]
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"))
    assert [c["field"] for c in out["added"]] == ["brand_new_input"]
    assert [(t["direction"], t["rows"], t["fields"], t["matched"]) for t in out["tables"]] == [
        ("input", 3, 3, 2),
        ("output", 3, 3, 3),
    ]
    assert all(t["spec"] > 10 for t in out["tables"])


def test_form_can_be_forced_and_a_wrong_form_reads_nothing(tmp_path: Path) -> None:
    path = tmp_path / "guide.txt"
    path.write_text(RENDERED)
    assert _json(str(path), "--form", "rendered-text", "--spec-dir", str(ROOT / "spec"))["format"] == (
        "rendered-text"
    )
    result = _cli(str(path), "--form", "markdown", "--spec-dir", str(ROOT / "spec"))
    assert result.returncode == 2
    assert "no field read" in result.stderr and "Name, Type, Comment" in result.stderr


def test_xlsx_workbook_every_sheet(spec: Spec, tmp_path: Path) -> None:
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    inputs = book.active
    inputs.title = "RTDE inputs"
    inputs.append(["Robot Controller Inputs"])
    inputs.append(["Name", "Type", "Comment", "Introduced in version"])
    inputs.append(["speed_slider_fraction", "DOUBLE", "New speed slider value", None])
    outputs = book.create_sheet("RTDE outputs")
    outputs.append(["Robot Controller Outputs"])
    outputs.append(["Name", "Type", "Comment", "Introduced in version"])
    outputs.append(["actual_q", "VECTOR6D", "Actual joint positions", None])
    outputs.append(["actual_tcp_jerk", "VECTOR6D", "Actual TCP jerk", "5.30.0"])
    outputs.append(["… and more", None, None, None])
    path = tmp_path / "Client_Interface.xlsx"
    book.save(path)
    doc = read_document(path, spec)
    assert doc.format == "xlsx"
    assert [(f.direction, f.name) for f in doc.fields] == [
        ("input", "speed_slider_fraction"),
        ("output", "actual_q"),
        ("output", "actual_tcp_jerk"),
    ]
    assert [t.skipped for t in doc.tables] == [[], [(5, "… and more")]]
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"))
    assert [c["field"] for c in out["added"]] == ["actual_tcp_jerk"]
    # the outputs table stops early: its missing rows are not removals; the inputs table is whole
    assert {c["where"] for c in out["removed"]} == {"input"} and out["unlisted"]["output"]
    # not a workbook at all: a clear error, not a zipfile traceback
    bad = tmp_path / "broken.xlsx"
    bad.write_bytes(b"PK\x03\x04 not really")
    result = _cli(str(bad), "--spec-dir", str(ROOT / "spec"))
    assert result.returncode == 2 and "not a readable .xlsx" in result.stderr
    assert "Traceback" not in result.stderr


MARKDOWN = """# Abridged copy

## Robot Controller Outputs

| Name | Type | Comment | Introduced in version |
|---|---|---|---|
| timestamp | DOUBLE | Time elapsed since the controller was started [s] | |
| actual_q | VECTOR6D | Actual joint positions | |
| … and more fields … | | | |
"""


def test_placeholder_rows_are_skipped_and_a_short_table_removes_nothing(tmp_path: Path) -> None:
    path = tmp_path / "abridged.md"
    path.write_text(MARKDOWN)
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"))
    assert out["tables"][0]["skipped"] == [{"line": 9, "cell": "… and more fields …"}]
    assert out["added"] == [] and out["removed"] == []
    assert len(out["unlisted"]["output"]) > 50 and "input" not in out["unlisted"]
    text = _cli(str(path), "--spec-dir", str(ROOT / "spec")).stdout
    assert "1 placeholder rows skipped" in text and "stops early" in text


def test_no_field_table_is_exit_2_naming_what_was_looked_for(tmp_path: Path) -> None:
    path = tmp_path / "notes.md"
    path.write_text("| Name | Age |\n|---|---|\n| a | 1 |\n")
    result = _cli(str(path), "--spec-dir", str(ROOT / "spec"))
    assert result.returncode == 2 and "looked for an RTDE field table" in result.stderr
    page = tmp_path / "primary.txt"
    page.write_text("Sub Package of Robot State\nnothing else here\n")
    result = _cli(str(page), "--spec-dir", str(ROOT / "spec"))
    assert result.returncode == 2 and "no message table read" in result.stderr


def test_edition_bounds_what_counts_as_removed(tmp_path: Path) -> None:
    """A 5.9-era guide listing two fields does not remove the fields 5.10+ added."""
    rows = "\n".join(
        f"| {n} | {t} | x | {v} |"
        for n, t, v in (("timestamp", "DOUBLE", "5.0.0"), ("ft_raw_wrench", "VECTOR6D", "5.9.0"))
    )
    path = tmp_path / "old.md"
    path.write_text(
        "## Robot Controller Outputs\n\n"
        "| Name | Type | Comment | Introduced in version |\n|---|---|---|---|\n" + rows + "\n"
    )
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--line", "e-series", "--allow-removals")
    assert out["edition"] == "5.9.0"
    removed = {c["field"] for c in out["removed"]}
    assert "actual_q" in removed and "collision_detection_ratio" not in removed  # 5.15.0 > 5.9.0
    later = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--line", "e-series", "--edition", "5.20")
    assert "collision_detection_ratio" in {c["field"] for c in later["removed"]}


def test_a_cb3_only_version_cell_is_no_change_for_e_series(tmp_path: Path) -> None:
    path = tmp_path / "cb3cells.md"
    path.write_text(
        "## Robot Controller Inputs\n\n| Name | Type | Comment | Introduced in version |\n|---|---|---|---|\n"
        "| speed_slider_mask | UINT32 | 0 = no change, 1 = use speed_slider_fraction | 3.3 |\n"
        "| input_int_register_X | INT32 | General purpose integer register X [0..47] "
        "| [0..23] 3.4.0 [24..47] 3.9.0 |\n| ... | | | |\n"
    )
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--line", "e-series")
    assert out["changed"] == [] and out["removed"] == []
    assert any("speed_slider_mask" in r and "names only older lines" in r for r in out["remarks"])


def test_hostile_html_is_refused_or_read_quickly_never_a_traceback(tmp_path: Path) -> None:
    start = time.perf_counter()
    assert read_tables("<table><![<![") == []
    assert read_tables("<table>" + "<a" * 200_000) == []
    assert time.perf_counter() - start < 10  # html.parser alone took 118 s on the second
    for text in ("<table><![<![", "<table><!--", "<table><tr><td>x<" * 3):
        path = tmp_path / "page.html"
        path.write_text(text)
        result = _cli(str(path), "--spec-dir", str(ROOT / "spec"))
        assert result.returncode == 2 and "Traceback" not in result.stderr, result.stderr
    many = "<h2>Outputs</h2><table><tr><th>Name</th><th>Type</th><th>Comment</th></tr>" + (
        "<tr><td>a</td><td>DOUBLE</td><td>x</td></tr>" * (MAX_ROWS + 5)
    )
    with pytest.raises(UsageError, match="table rows"):
        read_tables(many)


def test_a_recorded_conflict_hides_only_its_own_documents_change(spec: Spec, tmp_path: Path) -> None:
    """joint_position_deviation_ratio's removal is a known conflict of the crate README (its table
    stops early); the same removal in UR's own guide is a real change and is reported."""
    rows = [
        f"| {e.name.replace('{X}', 'X')} | {e.type} | {e.doc or 'x'} | |"
        for e in spec.fields.outputs
        if e.name != "joint_position_deviation_ratio"
    ]
    path = tmp_path / "outputs.md"
    path.write_text(HEAD_OUT + "\n".join(rows) + "\n")
    common = (str(path), "--spec-dir", str(ROOT / "spec"), "--line", "e-series", "--edition", "5.99")
    crate = _json(*common, "--source", "universal-robot-rust-crate-readme", "--show-known")
    assert "joint_position_deviation_ratio" not in {c["field"] for c in crate["removed"]}
    assert "joint_position_deviation_ratio" in {c["field"] for c in crate["known"]}
    guide = _json(*common, "--source", "e-series-guide")
    assert "joint_position_deviation_ratio" in {c["field"] for c in guide["removed"]}


HEAD_OUT = (
    "## Robot Controller Outputs\n\n| Name | Type | Comment | Introduced in version |\n|---|---|---|---|\n"
)


LISTING = """Client Interfaces
int messageSize
unsigned char messageType = ROBOT_STATE = 16

Joint data
int packageSize
unsigned char packageType = JOINT_DATA = 1
for each joint:
double q_actual
double q_target
double qd_actual
float I_actual
float V_actual
float T_motor
float T_micro
unsigned char jointMode
end

Cartesian info
int packageSize
unsigned char packageType = CARTESIAN_INFO = 4
double X
double Y
double Z
double Rx
double Ry
double Rz
"""


def test_docs_site_listing_with_for_each_joint_blocks(tmp_path: Path) -> None:
    """The docs site's C-like form: "for each joint: ... end" is the 6-times group, no version column."""
    path = tmp_path / "client-interfaces.txt"
    path.write_text(LISTING)
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--source", "a-listing-of-our-own")
    assert out["format"] == "primary-text"
    # the joint rows are read inside the repeated group: no "double in repeat 6 -> double" changes
    assert not [c for c in out["changed"] if c["what"] == "type"]
    assert [(c["field"], c["new"]) for c in out["added"]] == [("T_micro", "float in repeat 6")]
    removed = {c["field"] for c in out["removed"]}
    assert "joints.reserved" in removed and "tcp_offset_x" in removed  # fields newer than this listing
    assert not {f for f in removed if f.split(".")[-1] in {"q_actual", "jointmode", "joint_mode", "x", "rz"}}


DATA = Path(__file__).parent / "data" / "import"


def test_docs_site_primary_page_without_a_version_column(spec: Spec) -> None:
    """The docs site's 5.9 page: Field / Description only, the joint rows listed once (no
    "repeated" line), the edition named in its text ("Robot Software 5.9")."""
    doc = read_document(DATA / "primary_docs_site.txt", spec)
    assert (doc.format, doc.line, doc.edition) == ("primary-text", "e-series", "5.9.0")
    [joint] = doc.members
    assert (joint.family_type, joint.member_type) == (16, 1)
    assert [f.name for f in joint.fields][:3] == ["q_actual", "q_target", "qd_actual"]
    out = _json(str(DATA / "primary_docs_site.txt"), "--spec-dir", str(ROOT / "spec"))
    assert not [c for c in out["changed"] if c["what"] == "type"]  # no "double in repeat 6 -> double"
    assert sum("listed once, without the spec's group" in r for r in out["remarks"]) == 7


def test_for_each_joint_end_block_in_a_table_with_a_version_column(spec: Spec) -> None:
    doc = read_document(DATA / "primary_for_each_joint.txt", spec)
    [joint] = doc.members
    assert {f.group for f in joint.fields} == {"repeat 6"}
    assert [f.name for f in joint.fields][-1] == "jointMode"
    out = _json(str(DATA / "primary_for_each_joint.txt"), "--spec-dir", str(ROOT / "spec"))
    assert not [c for c in out["changed"] if c["what"] == "type"]


@pytest.mark.parametrize(
    ("text", "line", "edition", "newer"),
    [
        (
            "Universal Robots e-Series, software version 5.9\n",
            "e-series",
            "5.9.0",
            "collision_detection_ratio",
        ),
        ("Valid for software versions: 10.12.0, 5.25.0 and later.\n", "e-series", "5.25.0", None),
        ("CB3 Software version: from 3.4 forward\n", "cb3", "3.4.0", "collision_detection_ratio"),
        ("Client InterfacesV3.14andV5.9\n", "e-series", "5.9.0", "collision_detection_ratio"),
    ],
)
def test_the_edition_is_read_from_the_documents_own_text(
    tmp_path: Path, text: str, line: str, edition: str, newer: str | None
) -> None:
    """No version cells at all: the text's "software version" names the edition, and a field
    newer than it (collision_detection_ratio, 5.15.0) is not reported removed."""
    rows = "| timestamp | DOUBLE | Time elapsed since the controller was started [s] | |\n"
    path = tmp_path / "guide.md"
    path.write_text(text + "\n" + HEAD_OUT + rows)
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--line", line)
    assert out["edition"] == edition
    removed = {c["field"] for c in out["removed"]}
    assert newer is None or newer not in removed
    if line == "e-series":
        assert "actual_q" in removed  # inside the edition: a real removal
    # --edition still wins over the text
    later = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--line", line, "--edition", "5.20")
    assert later["edition"] == "5.20.0"


def test_numbers_that_are_no_software_version_are_not_an_edition(spec: Spec) -> None:
    from rtde_spec.importers.cells import Lines
    from rtde_spec.importers.edition import versions_named

    lines = Lines.of(spec)
    assert versions_named("the voltage exceeds 5.5 V; scale 3.3 times", lines) == {}
    assert versions_named("Robot Software 5.9 and CB3 3.15", lines) == {"e-series": "5.9.0", "cb3": "3.15.0"}
    assert versions_named("RealTime 5.10", lines) == {"e-series": "5.10.0"}


def test_listing_if_installed_group_closes_on_its_last_row(tmp_path: Path) -> None:
    """'(if euromap67 interface is installed, also the following: ... short euromapCurrent)':
    the row that closes the parenthesis is read, inside the group; the next row is outside it."""
    path = tmp_path / "listing.txt"
    path.write_text(
        "Masterboard data\nint packageSize\nunsigned char packageType = MASTERBOARD_DATA = 3\n"
        "char euromap67InterfaceInstalled\n(if euromap67 interface is installed, also the following:\n"
        "int euromapInputBits\nshort euromapCurrent)\nfloat afterTheGroup\n"
    )
    from rtde_spec.importers.primary_listing import read_listing

    [member] = read_listing(path.read_text())
    assert [(f.name, f.group) for f in member.fields] == [
        ("euromap67InterfaceInstalled", ""),
        ("euromapInputBits", "when euromap67interfaceinstalled"),  # the row naming the interface
        ("euromapCurrent", "when euromap67interfaceinstalled"),
        ("afterTheGroup", ""),
    ]


PRIMARY_HTML = """<html><body><h1>Primary and Secondary Interfaces</h1><p>Robot Software 5.9</p>
<h3>Joint Data (Sub Package of Robot State Message)</h3>
<table><tr><th>Field</th><th>Description</th></tr>
<tr><td>int packageSize</td><td></td></tr>
<tr><td>unsigned char packageType</td><td>ROBOT_STATE_PACKAGE_TYPE_JOINT_DATA = 1</td></tr>
<tr><td>double q_actual</td><td></td></tr>
<tr><td>double q_target</td><td></td></tr>
<tr><td>double qd_actual</td><td></td></tr>
<tr><td>float I_actual</td><td></td></tr>
<tr><td>float V_actual</td><td></td></tr>
<tr><td>float T_motor</td><td></td></tr>
<tr><td>float T_micro</td><td>Deprecated - ignore</td></tr>
<tr><td>uint8_t jointMode</td><td>Joint Modes</td></tr>
</table></body></html>
"""


@pytest.mark.parametrize("suffix", [".html", ".md"])
def test_the_primary_page_as_html_or_markdown(spec: Spec, tmp_path: Path, suffix: str) -> None:
    """The docs site's primary page saved as HTML, or converted to Markdown: Field | Description."""
    text = PRIMARY_HTML
    if suffix == ".md":
        from rtde_spec.importers.html_doc import read_tables as html_tables

        [table] = html_tables(PRIMARY_HTML)
        rows = "\n".join(f"| {' | '.join(cells)} |" for _, cells in table.rows)
        text = f"Robot Software 5.9\n\n### {table.heading}\n\n| Field | Description |\n|---|---|\n{rows}\n"
    path = tmp_path / f"primary{suffix}"
    path.write_text(text)
    doc = read_document(path, spec)
    assert (doc.interface, doc.edition) == ("primary", "5.9.0")
    [joint] = doc.members
    assert (joint.family_type, joint.member_type, len(joint.fields)) == (16, 1, 8)
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"), "--show-known")
    assert not [c for c in out["changed"] if c["what"] == "type"]
    assert not out["added"] and not out["removed"]
    # T_micro is the 5.9 edition's name of the spec's joints.reserved: a recorded conflict
    known = {(c["field"], c["what"]) for c in out["known"]}
    assert known == {("T_micro", "added"), ("joints.reserved", "removed")}


def test_a_data_types_table_after_the_outputs_ends_them(spec: Spec, tmp_path: Path) -> None:
    """The support article's outputs header splits "Introduced / in version" over two lines, and
    its Data types table (Name, Type, Size in bits) follows the outputs: no field "Size"."""
    text = RENDERED.replace("Introduced in version\n\ntimestamp", "Introduced\n\nin version\n\ntimestamp")
    text += "\n\n**Data types**\n\nName\n\nType\n\nSize in bits\n\nBOOL\n\n"
    text += "0 = False, everything else = True\n\n8\n"
    path = tmp_path / "guide.txt"
    path.write_text(text)
    doc = read_document(path, spec)
    assert [f.name for f in doc.fields if f.direction == "output"] == ["timestamp", "actual_q", "payload"]
    payload = next(f for f in doc.fields if f.name == "payload")
    assert (payload.version_text, payload.doc) == ("3.11.0 / 5.0.0", "Payload mass Kg")


def test_an_abridged_markdown_copy_with_names_in_code(spec: Spec) -> None:
    """The shape of an abridged copy of the e-Series guide: names in `code`, a comment naming only
    the upper register range, a blank cell for a 5.23 field, a placeholder row ending the outputs."""
    path = DATA / "abridged_guide.md"
    doc = read_document(path, spec)
    assert [f.name for f in doc.fields] == [
        "speed_slider_mask",
        "input_int_register_{X}",
        "timestamp",
        "actual_TCP_acceleration",
    ]
    register = doc.fields[1]
    assert register.index is None  # "[24..47]" in the comment is one range of 48 registers, not the family's
    assert doc.edition == "5.23.0"  # it lists actual_TCP_acceleration, which the spec has from 5.23.0
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"))
    assert (out["added"], out["changed"]) == ([], [])  # no "range [0, 47] -> [24, 47]"
    # the inputs table has no placeholder: what it leaves out is reported; the outputs stop early
    assert {c["where"] for c in out["removed"]} == {"input"} and len(out["unlisted"]["output"]) > 50
    assert out["tables"][1]["skipped"] == [{"line": 20, "cell": "… *and more fields* …"}]
    assert any("actual_TCP_acceleration: blank version cell" in r for r in out["remarks"])


def test_write_refuses_a_document_of_two_interfaces(tmp_path: Path) -> None:
    """A workbook with an RTDE sheet and a primary listing sheet: --write edits one interface's
    file at a time, so it is refused (nothing written) and the report still lists both."""
    openpyxl = pytest.importorskip("openpyxl")
    import shutil

    book = openpyxl.Workbook()
    rtde = book.active
    rtde.title = "RTDE outputs"
    rtde.append(["Robot Controller Outputs"])
    rtde.append(["Name", "Type", "Comment", "Introduced in version"])
    rtde.append(["actual_tcp_jerk", "VECTOR6D", "Actual TCP jerk", "5.30.0"])
    rtde.append(["… and more", None, None, None])
    listing = book.create_sheet("5.9")
    for line in [
        "Cartesian info",
        "int packageSize",
        "unsigned char packageType = CARTESIAN_INFO = 4",
        "double X",
    ]:
        listing.append([line])
    path = tmp_path / "Client_Interface.xlsx"
    book.save(path)
    tree = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", tree)
    before = {p: p.read_bytes() for p in tree.rglob("*.yaml")}
    out = _json(str(path), "--spec-dir", str(tree))
    assert out["interfaces"] == ["rtde", "primary"]
    result = _cli(str(path), "--spec-dir", str(tree), "--write")
    assert result.returncode == 2 and "one interface at a time" in result.stderr
    assert {p: p.read_bytes() for p in tree.rglob("*.yaml")} == before


def test_listing_arrays_as_one_row_blocks_and_length_prefixed_strings(tmp_path: Path) -> None:
    """The workbook's listing writes double[6] as "for each joint:" over one indented row, and a
    string as its size then "char array name": both read as the spec spells them."""
    path = tmp_path / "listing.txt"
    path.write_text(
        "Configuration data\nint packageSize\nunsigned char packageType = CONFIGURATION_DATA = 6\n"
        "for each joint:\n   double DHa\nfor each joint:\n   double DHd\ndouble afterThem\n"
        "VersionMessage\nint messageSize\nunsigned char messageType = ROBOT_MESSAGE = 20\n"
        "uint64_t timestamp\nchar source\nchar robotMessageType = ROBOT_MESSAGE_VERSION = 3\n"
        "char projectNameSize\nchar array projectName\nunsigned char majorVersion\n"
    )
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"))
    changed = {(c["field"], c["what"]) for c in out["changed"]}
    assert ("dh_a", "type") not in changed and ("dh_d", "type") not in changed
    assert ("project_name", "type") not in changed
    assert "projectNameSize" not in {c["field"] for c in out["added"]}


def test_a_for_each_joint_block_without_end_or_indent_is_reported(tmp_path: Path) -> None:
    """One copy of the workbook lost the indent that ends its blocks: the rows are still read,
    and the report says where a block's end is a guess."""
    path = tmp_path / "listing.txt"
    path.write_text(
        "Configuration data\nint packageSize\nunsigned char packageType = CONFIGURATION_DATA = 6\n"
        "for each joint:\ndouble jointMinLimit\ndouble jointMaxLimit\ndouble vJointDefault\n"
    )
    out = _json(str(path), "--spec-dir", str(ROOT / "spec"))
    assert any(r.startswith("line 4: 'for each joint:' has no 'end'") for r in out["remarks"])
    indented = tmp_path / "indented.txt"
    indented.write_text(path.read_text().replace("double joint", "   double joint"))
    assert not any(
        "has no 'end'" in r for r in _json(str(indented), "--spec-dir", str(ROOT / "spec"))["remarks"]
    )
