"""spec import on name cells that hold more than a name: said with the cell and line, not cut.

The name read was the cell's first word: `name#hash` became a field `name`, `weird name: here`
a field `weird`, and nothing said so. A footnote mark after a name (`[^1]`, `¹`, `*`) is still
no part of it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import Spec

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _doc(tmp_path: Path, *names: str) -> Path:
    lines = [
        "# Robot Controller Outputs",
        "",
        "| Name | Type | Comment | Introduced in version |",
        "|---|---|---|---|",
    ]
    lines += [f"| {n} | DOUBLE | A value |  |" for n in ("timestamp", *names)]
    path = tmp_path / "guide.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize(
    ("cell", "tail", "cut"), [("name#hash", "#hash", "name"), ("weird name: here", "name: here", "weird")]
)
def test_a_name_cell_with_more_than_a_name_is_said(
    tmp_path: Path, spec: Spec, cell: str, tail: str, cut: str
) -> None:
    doc = read_document(_doc(tmp_path, cell), spec)
    assert (
        f"line 6: the name cell {cell!r} holds more than a name ({tail!r} after {cut!r}): not read"
        in doc.problems
    )
    assert [f.name for f in doc.fields] == ["timestamp"]


@pytest.mark.parametrize(
    "cell", ["actual_q[^1]", "**actual_q**[^2]", "actual_q¹", "actual_q *", "`actual_q`"]
)
def test_a_footnote_mark_after_a_name_is_no_part_of_it(tmp_path: Path, spec: Spec, cell: str) -> None:
    doc = read_document(_doc(tmp_path, cell), spec)
    assert doc.problems == [] and [f.name for f in doc.fields] == ["timestamp", "actual_q"]


@pytest.mark.parametrize(
    "cell", ["actual_<br>joint_voltage", "actual_joint<br/>_voltage", "actual_<br>\njoint_voltage"]
)
def test_a_name_broken_by_a_line_break_beside_an_underscore(tmp_path: Path, spec: Spec, cell: str) -> None:
    """A saved page's narrow column with `<br>` in a name: read as 'actual_ joint_voltage', which
    was cut to 'actual_' (or, once said, not read)."""
    page = (
        "<html><body><h2>Robot Controller Outputs</h2><table><tr><th>Name</th><th>Type</th><th>Comment</th>"
        "<th>Introduced in version</th></tr>"
        f"<tr><td>{cell}</td><td>VECTOR6D</td><td>Actual joint voltages</td><td></td></tr>"
        "</table></body></html>"
    )
    path = tmp_path / "guide.html"
    path.write_text(page, encoding="utf-8")
    doc = read_document(path, spec)
    assert [f.name for f in doc.fields] == ["actual_joint_voltage"] and doc.problems == []
