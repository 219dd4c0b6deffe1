"""spec import reads UR's interface PDFs as a text extractor gives them (pdftotext).

ClientInterfaces_Primary.pdf holds two editions ("2. Robot Software 5.9", "3. Robot Software
5.10"), repeats page headers inside tables, loses some type numbers ("= MESSAGE_TYPE_ROBOT_MESSAGE
="), wraps names at an underscore, writes names in words ("uint8_t output mode"), moves a
sub-package's type line below the next message, and puts each row's description beside it
(pdftotext -layout). ClientInterfaces_Realtime.pdf wraps its header cells ("Number of" /
"values"). The documents here are our own, in those shapes.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.importers.primary_diff import diff_primary
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import Spec

ROOT = Path(__file__).resolve().parent.parent
PDF_TEXT = ROOT / "tests" / "data" / "import" / "primary_pdf_two_editions.txt"


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def test_the_newest_edition_of_a_two_edition_pdf_is_read(spec: Spec) -> None:
    doc = read_document(PDF_TEXT, spec)
    assert (doc.source, doc.line, doc.edition) == ("primary-guide", "e-series", "5.10.0")
    assert any("section 'Robot Software 5.9': 1 message tables of an older edition" in r for r in doc.remarks)
    types = [(m.family_type, m.member_type) for m in doc.members]
    # the version message's lost number comes from the spec's MessageType enum; Singularity Info's
    # type line, printed below the version message, goes back to it; "PROGRAM_LABEL_" / "THREADS"
    assert types == [(16, 1), (16, 12), (16, 13), (20, 3), (20, 14), (25, 0)]
    joint, tool_mode, singularity, version, threads, setup = doc.members
    assert [f.name for f in joint.fields][-2:] == ["T_micro", "jointMode"]  # the description column cut
    names = ["outputMode", "digtalOutputModeOutput0", "digtalOutputModeOutput1"]
    assert [f.name for f in tool_mode.fields] == names
    assert [f.name for f in singularity.fields] == ["singularitySeverity", "singularityType"]
    assert [f.type for f in version.fields if f.name == "projectName"] == ["string(uint8)"]  # charArray
    assert {f.group for f in threads.fields} == {"repeat until_end"}
    assert [f.name for f in setup.fields] == ["startIndex", "variableNames"]  # no repeat, no "float x"


def test_its_differences_are_the_recorded_conflicts_of_that_document(spec: Spec) -> None:
    changes = diff_primary(read_document(PDF_TEXT, spec), spec)
    assert changes and all(c.known is not None for c in changes)
    assert {c.field for c in changes} >= {"T_micro", "digtalOutputModeOutput0", "digital_output_mode_pin1"}
    other = diff_primary(read_document(PDF_TEXT, spec, source="someone-elses-table"), spec)
    assert {c.field for c in other if c.known is None} >= {"T_micro", "digtalOutputModeOutput0"}


REALTIME_PDF = """2. RealTime 5.9
(The RealTime interface has been deprecated since version 3.5.)
Meaning

Type

Number of
values

Size in
bytes

Gnuplot
col.

Notes

Message Size

integer

1

4

Time

double

1

8

1

Time elapsed since the controller was started

q target

double

6

48

2-7

Target joint positions

Tool vector
actual

double

6

48

8 - 13

Actual Cartesian coordinates of the tool
"""


def test_the_realtime_pdf_text_with_wrapped_cells(spec: Spec, tmp_path: Path) -> None:
    path = tmp_path / "realtime.txt"
    path.write_text(REALTIME_PDF)
    doc = read_document(path, spec)
    [table] = doc.realtime
    assert (table.edition, table.product_line) == ("5.9.0", "e-series")
    assert [r.key for r in table.rows] == ["time", "q_target", "tool_vector_actual"]
