"""The primary interface's differences with UR's own documents stay resolved.

spec/primary records, as sourced conflicts, what UR's 3.x client-interface workbook (and the
5.9/5.10 edition of the interface document) say differently: 3.x names (isRobotConnected,
T_micro, euromap67, analogInput2), `int` where the current document says uint32_t, messages
the current document dropped. Importing a listing of that shape must give only those known
conflicts; the same difference from another document family must still be reported. The
listings are our own, written in the workbook's shape (its text is not committed).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.importers.changes import Change
from rtde_spec.importers.primary_diff import diff_primary
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import Spec

ROOT = Path(__file__).resolve().parent.parent
LISTING_3_2 = ROOT / "tests" / "data" / "import" / "client_interface_3_2_listing.txt"


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _diff(path: Path, spec: Spec, **options: str) -> tuple[list[Change], list[Change], list[str]]:
    doc = read_document(path, spec, **options)  # type: ignore[arg-type]
    changes = diff_primary(doc, spec)
    return [c for c in changes if c.known is None], [c for c in changes if c.known is not None], doc.remarks


def test_a_3_2_workbook_listing_gives_only_known_conflicts(spec: Spec) -> None:
    new, known, remarks = _diff(LISTING_3_2, spec, line="cb3", edition="3.2")
    assert new == []
    found = {(c.where, c.what, c.field) for c in known}
    for expected in [
        ("robot_state/robot_mode_data", "added", "isRobotConnected"),
        ("robot_state/robot_mode_data", "removed", "is_real_robot_connected"),
        ("robot_state/joint_data", "added", "T_micro"),
        ("robot_state/joint_data", "removed", "joints.reserved"),
        ("robot_state/tool_data", "added", "analogInput2"),
        ("robot_state/force_mode_data", "removed", "frz"),
        ("robot_message/robot_comm_message", "type", "robot_message_code"),
        ("robot_message", "added", "LabelMessage"),
    ]:
        assert expected in found, expected
    assert all(c.known is not None and c.known.decision for c in known)
    # read, not guessed: requestedType's "= 0-8", the typed values of "for each variable",
    # a sub-package described in words only
    assert not {c.field for c in known} & {"requested_type", "variable_values", "checksum"}
    assert any("kinematics_info: listed without fields" in r for r in remarks)


@pytest.mark.parametrize("source", ["someone-elses-table", "primary-guide"])
def test_the_same_difference_from_another_document_family_is_still_reported(spec: Spec, source: str) -> None:
    """The conflicts belong to the workbook: a table of another family (the current interface
    document included) naming isRobotConnected or T_micro reports them."""
    new, _known, _ = _diff(LISTING_3_2, spec, line="cb3", edition="3.2", source=source)
    found = {(c.what, c.field) for c in new}
    assert ("added", "isRobotConnected") in found and ("removed", "is_real_robot_connected") in found
    assert ("added", "analogInput2") in found and ("added", "warningLevel") in found
    if source == "someone-elses-table":  # the 5.9 document says T_micro too: known for primary-guide
        assert ("added", "T_micro") in found


def test_a_changed_type_in_a_known_field_is_still_reported(spec: Spec, tmp_path: Path) -> None:
    """A conflict covers the difference it records (the document's value), not the field."""
    path = tmp_path / "listing.txt"
    path.write_text(LISTING_3_2.read_text().replace("bool isRobotConnected", "double isRobotConnected"))
    new, _known, _ = _diff(path, spec, line="cb3", edition="3.2")
    assert [(c.what, c.field, c.new) for c in new] == [("added", "isRobotConnected", "double")]


PRE_3_0 = """Masterboard data
int packageSize
unsigned char packageType = MASTERBOARD_DATA = 3
short digitalInputBits
short digitalOutputBits
char analogInputRange0
char analogInputRange1
double analogInput0
double analogInput1
char analogOutputDomain0
char analogOutputDomain1
double analogOutput0
double analogOutput1
float masterBoardTemperature
float robotVoltage48V
float robotCurrent
float masterIOCurrent
unsigned char masterSaftyState
unsigned char masterOnOffState
Tool data
int packageSize
unsigned char packageType = TOOL_DATA = 2
char analogInputRange2
char analogInputRange3
double analogInput2
unsigned char
"""


def test_a_pre_3_0_listing_is_compared_with_the_older_layout_and_a_cut_copy_says_so(
    spec: Spec, tmp_path: Path
) -> None:
    """The workbook's 1.x sheets (short digital bits, masterSaftyState) are compared with the
    spec's layout before 3.0 (python-urx's); a copy that ends inside a row compares nothing after it."""
    path = tmp_path / "listing.txt"
    path.write_text(PRE_3_0)
    new, known, remarks = _diff(path, spec, line="cb3", edition="1.8")
    assert new == []
    assert any("compared with the spec's layout before 3.0.0" in r for r in remarks)
    assert ("added", "masterSaftyState") in {(c.what, c.field) for c in known}
    assert any("tool_data analog_input1: after where the copy is cut short" in r for r in remarks)
    # with the current layout (a 3.x edition) the short bits are a type change
    new3, _, _ = _diff(path, spec, line="cb3", edition="3.2")
    assert ("type", "digital_input_bits", "int16") in {(c.what, c.field, c.new) for c in new3}


def test_a_block_without_end_or_indent_gives_remarks_not_type_changes(spec: Spec, tmp_path: Path) -> None:
    """A copy that lost its indents: rows after a 'for each joint:' block may or may not be in
    it; a type that differs from the spec only by that group is a remark."""
    path = tmp_path / "listing.txt"
    path.write_text(
        "Configuration data\nint packageSize\nunsigned char packageType = CONFIGURATION_DATA = 6\n"
        "for each joint:\ndouble jointMinLimit\ndouble jointMaxLimit\n"
        "for each joint:\ndouble jointMaxSpeed\ndouble jointMaxAcceleration\ndouble vJointDefault\n"
    )
    new, _known, remarks = _diff(path, spec, line="cb3", edition="3.2")
    assert not [c for c in new if c.what == "type"]
    assert any("vJointDefault: double in repeat 6 read in a block whose end is a guess" in r for r in remarks)
