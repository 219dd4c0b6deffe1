"""spec import reads the guide's PDF as pdftotext gives it, with and without -layout.

The two documents under data/import are real pdftotext output (poppler 22.12) of a PDF that
WeasyPrint made of a few of the e-Series seed's rows on A5 pages (data/import/make_pdf_text.py:
narrow name column, the header repeated on each page, a running title, "Page N of M"). Names
wrap at their `_`; without -layout, cells close together share a line ("UINT32 0 = don't
change ...") and pdftotext prints cells it cannot place apart from their rows.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from rtde_spec.importers import detect_format, read_document
from rtde_spec.importers.model import DocField, Document
from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_realworld import ESERIES, ROOT, _cli, seed, spec

__all__ = ["seed", "spec"]  # the module fixtures, shared

DATA = Path(__file__).parent / "data" / "import"
PLAIN = DATA / "pdf_plain.txt"
LAYOUT = DATA / "pdf_layout.txt"
#: the rows make_pdf_text.py put in the PDF, in its order
ROWS = {
    "input": ["speed_slider_mask", "standard_digital_output_mask", "input_bit_registers0_to_31",
              "input_int_register_{X}", "external_force_torque"],
    "output": ["timestamp", "actual_q", "actual_current_as_torque", "actual_TCP_acceleration", "robot_mode",
               "safety_mode", "actual_joint_voltage", "actual_configurable_digital_output_bits",
               "output_int_register_{X}", "payload_cog", "script_control_line", "target_base_acceleration"],
}  # fmt: skip

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")


@pytest.fixture(scope="module")
def guide(spec: Spec, tmp_path_factory: pytest.TempPathFactory) -> dict[tuple[str, str], DocField]:
    """The seed's rows, by (name, direction): what the PDF was made of."""
    doc = read_document(ESERIES, spec)
    return {(f.name, f.direction): f for f in doc.fields}


def _listed(doc: Document) -> dict[str, list[str]]:
    return {d: [f.name for f in doc.fields if f.direction == d] for d in ("input", "output")}


# -layout: columns


def test_layout_is_recognised_and_read_as_the_seed(spec: Spec, guide: dict) -> None:
    text = LAYOUT.read_text(encoding="utf-8")
    assert detect_format(text) == "columns-text"
    doc = read_document(LAYOUT, spec)
    assert doc.format == "columns-text" and doc.problems == []
    assert _listed(doc) == ROWS  # "standard_" / "digital_" / "output_" / "mask" and every other wrap rejoined
    for f in doc.fields:
        want = guide[(f.name, f.direction)]
        assert (f.type, f.doc, f.notes, f.index) == (want.type, want.doc, want.notes, want.index), f.name
    # the comment of the page's last row goes on under the next page's header
    assert next(f for f in doc.fields if f.name == "target_base_acceleration").doc.endswith(
        "URScript function."
    )


def test_layout_form_can_be_named(tmp_path: Path) -> None:
    out = _cli(LAYOUT, "--form", "columns-text", "--json")
    assert out.returncode == 0, out.stderr
    assert '"format": "columns-text"' in out.stdout and '"problems": []' in out.stdout


# without -layout: a cell per paragraph


def test_plain_names_are_rejoined_and_nothing_is_misread(spec: Spec, guide: dict) -> None:
    doc = read_document(PLAIN, spec)
    assert doc.format == "rendered-text"
    assert _listed(doc) == ROWS  # "speed_" / "slider_mask", "actual_" / "configurable_" / ... rejoined
    for f in doc.fields:
        want = guide[(f.name, f.direction)]
        assert f.type == want.type, f.name
        # a cell pdftotext moved away is missing here (and reported), never another row's
        assert f.doc in ("", want.doc) or want.doc.startswith(f.doc), f.name
        assert f.notes in ([], want.notes), f.name
    text = "\n".join(doc.problems)
    assert "pdftotext -layout" in text
    lines = PLAIN.read_text(encoding="utf-8").split("\n")
    for cell in ("Standard digital output bit", "48 general purpose integer", "[24..47]"):
        at = next(n for n, line in enumerate(lines, start=1) if line.startswith(cell))
        assert re.search(rf"line {at}: '{re.escape(cell)}", text), cell


def test_plain_check_fails_and_write_refuses(tmp_path: Path) -> None:
    shutil.copytree(ROOT / "spec", tmp_path / "spec")
    before = (tmp_path / "spec" / "rtde" / "fields.yaml").read_text(encoding="utf-8")
    out = _cli(PLAIN, "--check", "--spec-dir", tmp_path / "spec")
    assert out.returncode == 1 and "pdftotext -layout" in out.stderr
    out = _cli(PLAIN, "--write", "--allow-removals", "--spec-dir", tmp_path / "spec")
    assert out.returncode != 0 and "nothing written" in out.stderr and "pdftotext -layout" in out.stderr
    assert (tmp_path / "spec" / "rtde" / "fields.yaml").read_text(encoding="utf-8") == before


# the rule for rejoining


def test_wrap_rule(spec: Spec) -> None:
    from rtde_spec.importers.wrapped import join_parts, joins, known_names

    known = known_names(spec)
    assert joins("actual_joint_", "voltage", known)  # a name never ends in `_`
    assert joins("input_bit_registers0", "_to_31", known)  # nor starts with one
    assert joins("actual_tool_accelero", "meter", known)  # inside a word: a name the spec knows
    assert joins("actual_tcp_je", "rk", known) is None  # inside a word, unknown: cannot be told
    assert joins("timestamp", "actual_q", known) is None
    assert joins("Reserved", "speed_scaling", known, inside_word=False) is False  # a cell, then a name
    assert joins("Target joint", "positions", known) is False  # words, not a name
    assert join_parts(["input_int_", "register_X", "(X=[0..48])"], known) == (
        ["input_int_register_X (X=[0..48])"],
        [],
    )
    assert join_parts(["robot_mode", "joint_mode"], known) == (["robot_mode", "joint_mode"], [1])


def _one_per_line(rows: dict[str, list[list[str]]], wrap: dict[str, list[str]]) -> str:
    """A print to text of the page: a cell per line, no blank lines, some names wrapped."""
    lines = ["Real-Time Data Exchange (RTDE) Guide"]
    for direction, heading in (("input", "Robot Controller Inputs"), ("output", "Robot Controller Outputs")):
        lines += [heading, "Name", "Type", "Comment", "Introduced in version"]
        for name, type_, comment, version in rows[direction]:
            lines += wrap.get(name, [name]) + [type_] + [c for c in (comment, version) if c]
    return "\n".join([*lines, "Data types", "The types are sent in network byte order."]) + "\n"


def test_one_cell_per_line_with_wrapped_names(tmp_path: Path, spec: Spec) -> None:
    rows = {
        "input": [["speed_slider_mask", "UINT32", "New speed slider mask", ""]],
        "output": [
            ["timestamp", "DOUBLE", "Time elapsed since the controller was started [s]", ""],
            ["actual_joint_voltage", "VECTOR6D", "Actual joint voltages [V]", ""],
            ["actual_tool_accelerometer", "VECTOR3D", "Tool x, y, and z accelerometer values", ""],
            ["brand_new_output_field", "DOUBLE", "A field of a future release", "5.30.0"],
        ],
    }
    wrap = {
        "actual_joint_voltage": ["actual_joint_", "voltage"],
        "actual_tool_accelerometer": ["actual_tool_accelero", "meter"],  # inside a word, a known name
        "brand_new_output_field": ["brand_new_output_fi", "eld"],  # inside a word, unknown: reported
    }
    path = tmp_path / "printed.txt"
    text = _one_per_line(rows, wrap)
    path.write_text(text, encoding="utf-8")
    doc = read_document(path, spec)
    names = [f.name for f in doc.fields]
    assert names[:4] == [
        "speed_slider_mask",
        "timestamp",
        "actual_joint_voltage",
        "actual_tool_accelerometer",
    ]
    assert "actual_joint_" not in names and "voltage" not in names
    at = text.split("\n").index("brand_new_output_fi") + 1
    assert any(f"line {at}: 'brand_new_output_fi' / 'eld'" in p for p in doc.problems)
    assert _cli(path, "--check").returncode == 1
