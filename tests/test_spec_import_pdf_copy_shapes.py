"""spec import on what a copy from a PDF viewer does to the text: ligatures, and the like.

A PDF's text layer gives "ﬁ", "ﬂ", "ﬀ" as one character each; copied (or run through pdftotext)
`configurable_digital_output` reads `conﬁgurable_digital_output`, and was taken for a field
`con` (every name with fi/fl/ff "removed").
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_cut_pages import _fields, rendered
from tests.test_spec_import_realworld import ESERIES, _read, rows, seed, spec

__all__ = ["rows", "seed", "spec"]  # the module fixtures, shared

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")

LIGATURES = {"ffi": "\ufb03", "ffl": "\ufb04", "ff": "\ufb00", "fi": "\ufb01", "fl": "\ufb02"}


def _ligatures(text: str) -> str:
    for letters, ligature in LIGATURES.items():
        text = text.replace(letters, ligature)
    return text


def test_ligatures_read_as_their_letters(tmp_path: Path, seed: str, spec: Spec) -> None:
    copy = _ligatures(seed)
    assert "conﬁgurable_digital_output" in copy and "tcp_oﬀset" in copy
    plain = _read(tmp_path, "plain.txt", seed, spec)
    doc = _read(tmp_path, "copied.txt", copy, spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []


def _name_cells(seed: str, mark: object) -> str:
    """The seed with every name cell (the line before a type cell) changed by `mark`."""
    lines = seed.split("\n")
    types = {"UINT32 |", "UINT8 |", "DOUBLE |", "VECTOR6D |", "INT32 |", "BOOL |", "UINT64 |", "VECTOR3D |"}
    for k in range(len(lines) - 1):
        if lines[k + 1] in types and re.fullmatch(r"[a-z]\w* \|", lines[k]):
            lines[k] = mark(lines[k])  # type: ignore[operator]
    return "\n".join(lines)


@pytest.mark.parametrize("quotes", ["‘’", "“”", "''"])
def test_quoted_name_cells_read_as_the_names(tmp_path: Path, seed: str, spec: Spec, quotes: str) -> None:
    """A copy that quotes the names (smart quotes from a word processor): the rows were not found."""
    copy = _name_cells(seed, lambda line: f"{quotes[0]}{line[:-2]}{quotes[1]} |")
    plain = _read(tmp_path, "plain.txt", seed, spec)
    doc = _read(tmp_path, "quoted.txt", copy, spec)
    assert [f.name for f in doc.fields] == [f.name for f in plain.fields] and doc.problems == []


def test_pipe_cells_that_start_no_row_are_said(tmp_path: Path, seed: str, spec: Spec) -> None:
    """`• speed_slider_mask |` (a bullet before each name): no row starts, and every field of the
    table was "removed" with nothing said."""
    copy = _name_cells(seed, lambda line: f"• {line}")
    doc = _read(tmp_path, "bullets.txt", copy, spec)
    at = copy.split("\n").index("• speed_slider_mask |") + 1
    assert any(
        p.startswith(f"line {at}: '• speed_slider_mask' and ") and "start no row" in p for p in doc.problems
    )


@pytest.mark.parametrize(
    ("name", "broken"),
    [("actual_joint_voltage", "actual_joint_volt-\nage"), ("speed_slider_mask", "speed_slid-\ner_mask")],
)
def test_a_name_hyphenated_at_a_line_end_is_one_name(
    tmp_path: Path, rows: dict, spec: Spec, name: str, broken: str
) -> None:
    """A PDF viewer's copy breaks a long name in a narrow column with a hyphen: the part after the
    break was read as the name ('age') and the part before as the row above's comment."""
    text = rendered(rows)
    assert f"\n{name}\n" in text
    plain = _read(tmp_path, "plain.txt", text, spec)
    doc = _read(tmp_path, "copied.txt", text.replace(f"\n{name}\n", f"\n{broken}\n", 1), spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []
