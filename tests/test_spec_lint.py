"""Deliberately broken specs: each problem is reported with file, path, line and reason."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from rtde_spec.errors import SpecError
from rtde_spec.metamodel.loader import load_spec

from .helpers import ROOT


@pytest.fixture
def spec_copy(tmp_path: Path) -> Path:
    target = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", target)
    return target


def _edit(root: Path, rel: str, old: str, new: str) -> None:
    path = root / rel
    text = path.read_text()
    assert old in text, f"test setup: {old!r} not in {rel}"
    path.write_text(text.replace(old, new, 1))


def _issues(root: Path) -> list:
    with pytest.raises(SpecError) as info:
        load_spec(root)
    return info.value.issues


def test_the_real_spec_is_clean() -> None:
    spec = load_spec(ROOT / "spec")
    assert spec.fields.outputs and spec.packages.messages


RANGE_24 = "      - {index: [24, 47], since: {cb3: 3.9.0, e-series: 5.3.0}}\n"
NEXT = "    conflicts:\n"  # the first family with ranges and conflicts: inputs input_int_register_{X}
CASES: list[tuple[str, str, str, str, str, str]] = [
    # (id, file, old text, new text, expected path fragment, expected reason fragment)
    (
        "conflict range outside the family",
        "rtde/fields.yaml",
        "        index: [0, 23]\n        document:",
        "        index: [0, 99]\n        document:",
        "inputs[15](input_int_register_{X}).conflicts[0].index",
        "is outside the index [0, 47]",
    ),
    (
        "conflict without a decision",
        "rtde/fields.yaml",
        "        sources: [e-series-guide]\n        decision: \"The e-Series guide's version cell",
        "        sources: [e-series-guide]\n        decisoin: \"The e-Series guide's version cell",
        "conflicts[0]",
        "unknown key 'decisoin'",
    ),
    (
        "unknown key",
        "rtde/fields.yaml",
        "    unit: rad/s²\n",
        "    unti: rad/s²\n",
        "outputs[4](target_qdd)",
        "unknown key 'unti'",
    ),
    (
        "unknown type",
        "rtde/fields.yaml",
        "type: VECTOR6D\n    unit: rad\n    doc: Target joint positions",
        "type: VECTOR7D\n    unit: rad\n    doc: Target joint positions",
        "outputs[2](target_q).type",
        "unknown type 'VECTOR7D'",
    ),
    (
        "duplicate name",
        "rtde/fields.yaml",
        "  - name: target_qd\n",
        "  - name: target_q\n",
        "outputs[3](target_q).name",
        "duplicate name 'target_q'",
    ),
    (
        "bad version string",
        "rtde/fields.yaml",
        "since: {cb3: 3.10.0, e-series: 5.4.0}",
        "since: {cb3: 3.10, e-series: 5.4.0}",
        "since.cb3",
        "bad version string",
    ),
    (
        "bad version text",
        "rtde/fields.yaml",
        "since: {cb3: 3.10.0, e-series: 5.4.0}",
        "since: {cb3: three, e-series: 5.4.0}",
        "since.cb3",
        "bad version string 'three'",
    ),
    (
        "version on wrong line",
        "rtde/fields.yaml",
        "since: {cb3: 3.10.0, e-series: 5.4.0}",
        "since: {cb3: 5.10.0, e-series: 5.4.0}",
        "since.cb3",
        "not on line cb3",
    ),
    (
        "unknown product line",
        "rtde/fields.yaml",
        "since: {cb3: 3.10.0, e-series: 5.4.0}",
        "since: {cb2: 3.10.0, e-series: 5.4.0}",
        "since.cb2",
        "unknown product line 'cb2'",
    ),
    (
        "overlapping ranges",
        "rtde/fields.yaml",
        RANGE_24 + NEXT,
        RANGE_24.replace("24, 47", "20, 47") + NEXT,
        "inputs[15](input_int_register_{X}).ranges[1].index",
        "overlaps range 0",
    ),
    (
        "range outside index",
        "rtde/fields.yaml",
        RANGE_24 + NEXT,
        RANGE_24.replace("24, 47", "24, 48") + NEXT,
        "ranges[1].index",
        "outside the field's index",
    ),
    (
        "family without placeholder",
        "rtde/fields.yaml",
        "  - name: input_int_register_{X}\n",
        "  - name: input_int_register\n",
        "inputs[15](input_int_register).name",
        "needs {X}",
    ),
    (
        "unknown enum",
        "rtde/fields.yaml",
        "enum: RobotMode",
        "enum: RobotMood",
        "(robot_mode).enum",
        "unknown enum 'RobotMood'",
    ),
    (
        "unknown bitfield",
        "rtde/fields.yaml",
        "bits: RobotStatusBits",
        "bits: RobotStatusBytes",
        "(robot_status_bits).bits",
        "unknown bitfield",
    ),
    (
        "enum on a double",
        "rtde/fields.yaml",
        "    type: INT32\n    enum: RobotMode",
        "    type: DOUBLE\n    enum: RobotMode",
        "(robot_mode).enum",
        "non-integer type DOUBLE",
    ),
    (
        "unknown enum in package",
        "rtde/packages.yaml",
        "enum: TextMessageLevel, doc: Severity",
        "enum: TextLevel, doc: Severity",
        "messages[4](text_message_v1_controller).fields[0]",
        "unknown enum 'TextLevel'",
    ),
    (
        "duplicate enum value",
        "rtde/enums.yaml",
        "{name: CONFIRM_SAFETY, value: 1,",
        "{name: CONFIRM_SAFETY, value: 0,",
        "enums[0](RobotMode).values[1]",
        "duplicate value '0'",
    ),
    (
        "unknown package type",
        "rtde/packages.yaml",
        "    type: S\n    sender: client",
        "    type: X\n    sender: client",
        "(start).type",
        "unknown package type 'X'",
    ),
    (
        "ambiguous layouts",
        "rtde/packages.yaml",
        "    type: P\n    sender: client",
        "    type: S\n    sender: client",
        "(pause).protocols",
        "is also start",
    ),
    (
        "unknown primitive element",
        "rtde/types.yaml",
        "{name: UINT8, element: uint8,",
        "{name: UINT8, element: uint9,",
        "types[1](UINT8).element",
        "unknown primitive 'uint9'",
    ),
    (
        "member type not in its enum",
        "primary/interface.yaml",
        "      - name: key_message\n        type: 7\n",
        "      - name: key_message\n        type: 8\n",
        "families[1](robot_message).members[4](key_message).type",
        "robot_message member number 8 is not a value of RobotMessageType",
    ),
    (
        "rest field not last",
        "rtde/packages.yaml",
        "      - {name: message_type, type: uint8, enum: TextMessageLevel, doc: Severity}\n"
        '      - {name: message, type: string, length: rest, doc: "The text, to the end of the package"}',
        '      - {name: message, type: string, length: rest, doc: "The text, to the end of the package"}\n'
        "      - {name: message_type, type: uint8, enum: TextMessageLevel, doc: Severity}",
        "fields[0](message).length",
        "only the last field",
    ),
    (
        "primary field without a doc",
        "primary/interface.yaml",
        '{name: q_target, type: double, unit: rad, doc: "q_target: target joint position"}',
        "{name: q_target, type: double, unit: rad}",
        "members[1](joint_data).fields[0](joints).fields[1](q_target).doc",
        "field 'q_target' has no doc",
    ),
    (
        "rtde package field without a doc",
        "rtde/packages.yaml",
        '{name: recipe_id, type: uint8, doc: "The recipe whose layout the payload has '
        '(from its setup reply)"}',
        "{name: recipe_id, type: uint8}",
        "messages[7](data_package).fields[0](recipe_id)",
        "field 'recipe_id' has no doc",
    ),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_broken_spec_is_reported(spec_copy: Path, case: tuple[str, ...]) -> None:
    _, rel, old, new, path_part, reason_part = case
    _edit(spec_copy, rel, old, new)
    issues = _issues(spec_copy)
    matching = [i for i in issues if reason_part in i.reason and path_part in i.path]
    assert matching, f"no issue with {path_part!r} / {reason_part!r} in {issues}"
    issue = matching[0]
    assert issue.file == rel
    assert issue.line is not None and issue.line > 0
    assert rel in str(issue) and reason_part in str(issue)


def test_issue_line_points_at_the_problem(spec_copy: Path) -> None:
    _edit(spec_copy, "rtde/fields.yaml", "enum: RobotMode", "enum: RobotMood")
    issue = _issues(spec_copy)[0]
    line = (spec_copy / "rtde/fields.yaml").read_text().splitlines()[issue.line - 1]
    assert "RobotMood" in line


def test_all_problems_are_reported_at_once(spec_copy: Path) -> None:
    _edit(spec_copy, "rtde/fields.yaml", "enum: RobotMode", "enum: RobotMood")
    _edit(spec_copy, "rtde/fields.yaml", "bits: RobotStatusBits", "bits: Nope")
    reasons = " ".join(i.reason for i in _issues(spec_copy))
    assert "RobotMood" in reasons and "Nope" in reasons


def test_missing_file_and_bad_yaml(spec_copy: Path) -> None:
    (spec_copy / "rtde/enums.yaml").unlink()
    (spec_copy / "rtde/types.yaml").write_text("types: [\n")
    issues = _issues(spec_copy)
    assert any(i.file == "rtde/enums.yaml" and "not found" in i.reason for i in issues)
    assert any(i.file == "rtde/types.yaml" and "not valid YAML" in i.reason for i in issues)


def test_an_enum_value_without_its_member_is_reported_at_the_members(spec_copy: Path) -> None:
    _edit(spec_copy, "primary/enums.yaml", "      - {name: VERSION, value: 3}\n",
          "      - {name: VERSION, value: 3}\n      - {name: NEWER_THING, value: 4}\n")  # fmt: skip
    issues = _issues(spec_copy)
    (issue,) = [i for i in issues if "NEWER_THING" in i.reason]
    assert issue.file == "primary/interface.yaml" and "families[1](robot_message).members" in issue.path
    assert "RobotMessageType.NEWER_THING (4) has no robot_message member" in issue.reason
