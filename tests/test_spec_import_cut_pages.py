"""spec import on text copies cut short or broken by pages: said where, never read as removals.

The documents are the e-Series seed's rows in the shapes people copy them: the rendered page
(a cell per line, as a browser's copy or a print to text gives it), the tab form and the
seed's own `|` form; cut where a user's selection ends, or broken by a page's furniture.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from rtde_spec.importers.model import Document
from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_realworld import ESERIES, ROOT, _cli, _read, rows, seed, spec

__all__ = ["rows", "seed", "spec"]  # the module fixtures, shared

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")

HEADER = ["Name", "Type", "Comment", "Introduced in version"]
#: what follows the outputs table in the guide: an enum's section, then the data types
AFTER = ["Time Scale Source", "List of possible causes for time scaling.", "Value", "Description", "-1",
         "Other", "0", "Program is not running", "Safety Status",
         "Valid for software versions: 10.12.0, 5.25.0 and later."]  # fmt: skip


def rendered(rows: dict[str, list[list[str]]], before: str = "", furniture: tuple[str, ...] = ()) -> str:
    """The page copied from a browser: a cell per line; an empty cell leaves no line."""
    lines = ["Real-Time Data Exchange (RTDE) Guide", "Field Names and Associated Types"]
    for direction, heading in (("input", "Robot Controller Inputs"), ("output", "Robot Controller Outputs")):
        lines += [heading]
        if direction == "output":
            lines += [
                "NOTE: The robot controller requires that the client subscribes to at least one output."
            ]
        lines += HEADER
        for cells in rows[direction]:
            if cells[0] == before:
                lines += furniture
            lines += [c for c in cells if c]
    return "\n".join([*lines, *AFTER]) + "\n"


def _fields(doc: Document) -> list[tuple]:
    return [(f.name, f.direction, f.type, f.doc, f.notes, f.index) for f in doc.fields]


def _line(text: str, start: str) -> int:
    return next(n for n, line in enumerate(text.split("\n"), start=1) if line.startswith(start))


# the end of a table in the rendered form


def test_rendered_table_ends_after_its_last_row(tmp_path: Path, rows: dict, spec: Spec) -> None:
    doc = _read(tmp_path, "copied.txt", rendered(rows), spec)
    bare = "\n".join(rendered(rows).split("\n")[: -len(AFTER) - 1]).replace(
        "NOTE: The robot controller requires that the client subscribes to at least one output.\n", ""
    )
    plain = _read(tmp_path, "bare.txt", bare, spec)  # no note, nothing after the outputs
    assert _fields(doc) == _fields(plain) and doc.problems == [] == plain.problems
    last = {f.name: f for f in doc.fields}
    assert "NOTE" not in last["external_force_torque"].doc  # the next section's note is not its comment
    assert "Time Scale" not in last["target_base_acceleration"].doc
    out = _cli(tmp_path / "copied.txt", "--check")
    assert out.returncode == 0, out.stdout + out.stderr
    assert "0 added, 0 removed, 0 changed" in out.stdout


# a copy cut off inside a table


def _rendered_cut(rows: dict, stop: str) -> str:
    text = rendered(rows)
    return text[: text.index("\nactual_joint_voltage\n") + len(stop) + 1]


@pytest.mark.parametrize(
    "stop",
    [
        "actual_joint_voltage\nVECTOR6D\nActual joint vol",  # inside the comment
        "actual_joint_voltage\nVECTOR6D\n",  # before the comment
        "actual_joint_voltage\nVECT",  # inside the type
        "actual_joint_voltage",  # after the name
    ],
)
def test_rendered_copy_cut_inside_a_table(tmp_path: Path, rows: dict, spec: Spec, stop: str) -> None:
    text = _rendered_cut(rows, stop)
    doc = _read(tmp_path, "cut.txt", text, spec)
    names = [f.name for f in doc.fields]
    assert "actual_joint_voltage" not in names and names[-1] == "actual_robot_current"
    at = _line(text, "actual_joint_voltage")
    problem = " ".join(doc.problems)
    assert "ends inside the table 'Robot Controller Outputs'" in problem and f"line {at}" in problem
    assert [t.cut for t in doc.tables] == [False, True]


def _cut_is_refused(path: Path, tmp_path: Path, line: int) -> None:
    out = _cli(path, "--check", "--json")
    assert out.returncode == 1
    assert '"removed": []' in out.stdout  # the rows after the cut are not removals
    shutil.copytree(ROOT / "spec", tmp_path / "spec")
    before = (tmp_path / "spec" / "rtde" / "fields.yaml").read_text(encoding="utf-8")
    out = _cli(path, "--write", "--spec-dir", tmp_path / "spec")
    assert out.returncode != 0 and "nothing written" in out.stderr
    assert re.search(rf"ends inside the table 'Robot Controller Outputs' .*line {line}\b", out.stderr)
    assert (tmp_path / "spec" / "rtde" / "fields.yaml").read_text(encoding="utf-8") == before


def test_rendered_cut_is_checked_and_refused(tmp_path: Path, rows: dict) -> None:
    text = _rendered_cut(rows, "actual_joint_voltage\nVECTOR6D\nActual joint vol")
    (tmp_path / "cut.txt").write_text(text, encoding="utf-8")
    _cut_is_refused(tmp_path / "cut.txt", tmp_path, _line(text, "actual_joint_voltage"))


def test_pipe_copy_cut_inside_a_table(tmp_path: Path, seed: str) -> None:
    text = seed[
        : seed.index("\nactual_joint_voltage |\n") + len("\nactual_joint_voltage |\nVECTOR6D |\nActual")
    ]
    (tmp_path / "cut.txt").write_text(text, encoding="utf-8")
    _cut_is_refused(tmp_path / "cut.txt", tmp_path, _line(text, "actual_joint_voltage"))


def test_tab_copy_cut_inside_a_table(tmp_path: Path, rows: dict, spec: Spec) -> None:
    lines = ["Real-Time Data Exchange (RTDE) Guide"]
    for direction, heading in (("input", "Robot Controller Inputs"), ("output", "Robot Controller Outputs")):
        lines += [heading, "\t".join(HEADER), *("\t".join(cells) for cells in rows[direction])]
    text = "\n".join(lines)
    text = text[: text.index("\nactual_joint_voltage\t") + len("\nactual_joint_voltage\tVECTOR6D\tActual jo")]
    doc = _read(tmp_path, "cut.txt", text, spec)
    assert doc.fields[-1].name == "actual_robot_current"
    (tmp_path / "cut.txt").write_text(text, encoding="utf-8")
    _cut_is_refused(tmp_path / "cut.txt", tmp_path, _line(text, "actual_joint_voltage"))


def test_whole_copies_are_not_cut(tmp_path: Path, rows: dict, seed: str, spec: Spec) -> None:
    assert _read(tmp_path, "seed.txt", seed, spec).problems == []
    # ends at a whole row (its version cell given): the table's end as far as the text says
    text = rendered(rows)
    whole = text[: text.index("\n5.23.0 / 10.11.0\n") + len("\n5.23.0 / 10.11.0\n")]
    assert _read(tmp_path, "whole.txt", whole, spec).problems == []
    # ends in a placeholder: the copy says rows are left out
    abridged = text[: text.index("\nactual_joint_voltage\n") + 1] + "… and more fields …\n"
    doc = _read(tmp_path, "abridged.txt", abridged, spec)
    assert doc.problems == [] and not any(t.cut for t in doc.tables)


# page breaks in the rendered form


@pytest.mark.parametrize(
    "furniture",
    [
        ("Page 7 of 9", "RTDE Guide: inputs", *HEADER),  # a running header naming the other direction
        ("https://www.universal-robots.com/articles/ur/rtde-guide/", "4/9", "5/14/24, 10:15 AM",
         "Real-Time Data Exchange (RTDE) Guide"),  # a browser's print: address, page, date, title
        ("Page 7 of 9", "Robot Controller Outputs (continued)", *HEADER),
        ("Page 3 of 5", "\fReal-Time Data Exchange (RTDE) Guide", *HEADER),  # pdftotext's form feed
    ],
)  # fmt: skip
@pytest.mark.parametrize("before", ["joint_position_deviation_ratio", "tool_mode", "input_int_register_X"])
def test_page_break_inside_a_rendered_table(
    tmp_path: Path, rows: dict, spec: Spec, furniture: tuple[str, ...], before: str
) -> None:
    plain = _read(tmp_path, "plain.txt", rendered(rows), spec)
    doc = _read(tmp_path, "paged.txt", rendered(rows, before, furniture), spec)
    assert _fields(doc) == _fields(plain)
    assert [(t.direction, t.fields) for t in doc.tables] == [(t.direction, t.fields) for t in plain.tables]
    assert doc.problems == []
    assert any("goes on after a page break" in r for r in doc.remarks)


def test_a_cell_beside_a_page_break_is_reported(tmp_path: Path, rows: dict, spec: Spec) -> None:
    text = rendered(rows, "tool_mode", ("Page 7 of 9", "5.3.0", "Real-Time Data Exchange (RTDE) Guide"))
    doc = _read(tmp_path, "paged.txt", text, spec)
    at = _line(text, "Page 7 of 9") + 1
    assert any(f"line {at}: '5.3.0' after the page break at line {at - 1}" in p for p in doc.problems)
    assert _fields(doc) == _fields(_read(tmp_path, "plain.txt", rendered(rows), spec))
