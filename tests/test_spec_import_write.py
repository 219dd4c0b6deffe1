"""spec import --write and -o: hand-made changes to a guide land in spec/ and in `fields`.

The guide is written from today's spec in the e-Series text form, so it re-imports
clean; then five changes are made by hand and exactly those must be reported,
written into a copy of the tree, regenerated, and shown by `fields --controller`.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.cli.main import main
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import FieldSpec, Spec

ROOT = Path(__file__).resolve().parent.parent


def _cell(entry: FieldSpec) -> str | None:
    """The "introduced in" cell for the e-Series line, or None when the line lacks the field."""

    def one(since: dict[str, str] | None) -> str | None:
        if since is None:
            return ""
        if "e-series" not in since:
            return None
        text = since["e-series"] if since["e-series"] != "5.0.0" or "polyscope-x" in since else ""
        return f"{text} / {since['polyscope-x']}" if "polyscope-x" in since else text

    if entry.ranges:
        parts = []
        for rng in entry.ranges:
            text = one(rng.since if rng.since is not None else entry.since)
            if text:
                parts.append(f"[{rng.index[0]}..{rng.index[1]}] {text}")
        return " ".join(parts)
    return one(entry.since)


def guide_from_spec(spec: Spec) -> str:
    """Today's spec as the e-Series guide's text form (fields of third parties left out)."""
    out = ["Field Names and Associated Types"]
    for heading, entries in (
        ("Robot Controller Inputs", spec.fields.inputs),
        ("Robot Controller Outputs", spec.fields.outputs),
    ):
        out += [heading, "Name |", "Type |", "Comment |", "Introduced in Version |", "|---|---|---|---|"]
        for entry in entries:
            cell = _cell(entry)
            if cell is None or set(entry.sources) <= {"third-party", "user"}:
                continue
            doc = (entry.doc or "").replace("{X}", "X")
            if entry.index is not None:
                doc += f" (X: [{entry.index[0]}..{entry.index[1]}])"
            out += [f"{entry.name.replace('{X}', 'X')} |", f"{entry.type} |", f"{doc} |", f"{cell} |"]
    return "\n".join(out) + "\nData types\n"


def _row(text: str, name: str) -> tuple[int, int]:
    lines = text.split("\n")
    start = lines.index(f"{name} |")
    return start, start + 4


def hand_made(text: str) -> str:
    """A field added with a new version, one removed, one retyped, one moved, a range widened."""
    lines = text.split("\n")
    a, b = _row(text, "collision_detection_ratio")
    del lines[a:b]
    text = "\n".join(lines)
    text = text.replace("tool_temperature |\nDOUBLE |", "tool_temperature |\nINT32 |")
    text = text.replace(
        "time_scale_source |\nINT32 |\nCause of time scaling |\n5.17.0 |",
        "time_scale_source |\nINT32 |\nCause of time scaling |\n5.18.0 |",
    )
    old = "output_int_register_X |\nINT32 |\n"
    start = text.index(old)
    end = text.index("|\n", text.index("|\n", start + len(old)) + 2) + 2
    text = (
        text[:start]
        + (
            "output_int_register_X |\nINT32 |\nGeneral purpose integer register X: the lower range is "
            "reserved for the Fieldbus/PLC interface, the upper range can be used by external RTDE "
            "clients (e.g. URCaps) (X: [0..63]) |\n"
            "[24..47] 5.3.0 [48..63] 5.30.0 |\n"
        )
        + text[end:]
    )
    added = "actual_tcp_jerk |\nVECTOR6D |\nActual TCP jerk [m/s³] |\n5.30.0 / 10.15.0 |\n"
    return text.replace("Data types\n", added + "Data types\n")


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _import(path: Path, spec_dir: Path, *extra: str) -> tuple[int, dict[str, Any]]:
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "rtde_spec.cli",
            "spec",
            "import",
            str(path),
            "--spec-dir",
            str(spec_dir),
            "--json",
            *extra,
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    return result.returncode, json.loads(result.stdout)


def test_the_spec_written_as_a_guide_reimports_clean(spec: Spec, tmp_path: Path) -> None:
    guide = tmp_path / "guide.txt"
    guide.write_text(guide_from_spec(spec))
    code, out = _import(guide, ROOT / "spec")
    assert code == 0 and (out["added"], out["removed"], out["changed"]) == ([], [], []), out
    assert out["format"] == "e-series-text" and out["line"] == "e-series"


def test_exactly_the_hand_made_changes_are_reported(spec: Spec, tmp_path: Path) -> None:
    guide = tmp_path / "guide.txt"
    guide.write_text(hand_made(guide_from_spec(spec)))
    code, out = _import(guide, ROOT / "spec")
    assert code == 0
    assert [(c["field"], c["where"], c["new"]) for c in out["added"]] == [
        ("actual_tcp_jerk", "output", "VECTOR6D")
    ]
    assert [(c["field"], c["old"]) for c in out["removed"]] == [("collision_detection_ratio", "DOUBLE")]
    changed = {(c["field"], c["what"]): (c["old"], c["new"]) for c in out["changed"]}
    assert changed == {
        ("tool_temperature", "type"): ("DOUBLE", "INT32"),
        ("time_scale_source", "availability"): (
            {"e-series": "5.17.0", "polyscope-x": "10.0.0"},
            {"e-series": "5.18.0", "polyscope-x": "10.0.0"},
        ),
        ("output_int_register_{X}", "range"): ([0, 47], [0, 63]),
    }
    assert all(isinstance(c["line"], int) for c in out["added"] + out["changed"])


def _copy_tree(tmp_path: Path) -> Path:
    root = tmp_path / "tree"
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(ROOT / "spec", root / "spec")
    shutil.copytree(ROOT / "rtde_spec", root / "rtde_spec", ignore=ignore)
    return root


def _fields(root: Path, version: str) -> dict[str, dict[str, Any]]:
    env = {**os.environ, "PYTHONPATH": str(root)}
    result = subprocess.run(
        [sys.executable, "-m", "rtde_spec.cli", "fields", "--controller", version, "--json"],
        capture_output=True,
        text=True,
        cwd=root,
        env=env,
        check=True,
    )
    return {f"{f['direction']}:{f['name']}": f for f in json.loads(result.stdout)}


@pytest.mark.slow  # spec import --write, then codegen of the whole spec: 3.7 s CPU
def test_write_then_codegen_shows_the_changes_at_their_versions(spec: Spec, tmp_path: Path) -> None:
    root = _copy_tree(tmp_path)
    fields_yaml = root / "spec" / "rtde" / "fields.yaml"
    before = fields_yaml.read_text()
    guide = tmp_path / "guide.txt"
    guide.write_text(hand_made(guide_from_spec(spec)))
    code, _ = _import(guide, root / "spec", "--write", "--allow-removals")
    assert code == 0
    after = fields_yaml.read_text()
    assert after.splitlines()[:12] == before.splitlines()[:12]  # the header comment is kept
    assert "  - name: actual_tcp_jerk\n    type: VECTOR6D\n" in after
    assert "collision_detection_ratio" not in after
    # the spec is valid, regenerates, and passes --check
    for args in ([], ["--check"]):
        gen = subprocess.run(
            [sys.executable, "-m", "codegen", "--spec", str(root / "spec"), "--out", str(root), *args],
            capture_output=True,
            text=True,
            cwd=ROOT,
        )
        assert gen.returncode == 0, gen.stderr
    old, new = _fields(root, "5.29.0"), _fields(root, "5.30.0")
    assert "output:actual_tcp_jerk" in new and "output:actual_tcp_jerk" not in old
    assert new["output:actual_tcp_jerk"]["since"] == {"e-series": "5.30.0", "polyscope-x": "10.15.0"}
    assert "output:actual_tcp_jerk" in _fields(root, "10.15.0")
    assert "output:collision_detection_ratio" not in new
    assert new["output:tool_temperature"]["type"] == "INT32" and new["output:tool_temperature"]["size"] == 4
    assert "output:time_scale_source" not in _fields(root, "5.17.0")
    assert "output:time_scale_source" in _fields(root, "5.18.0")
    assert "output:output_int_register_63" in new and "output:output_int_register_63" not in old
    assert "output:output_int_register_47" in old
    # and the edited spec re-imports the document clean
    code, out = _import(guide, root / "spec")
    assert (out["added"], out["removed"], out["changed"]) == ([], [], [])


def test_overlay_adds_the_new_fields_to_an_installed_package(spec: Spec, tmp_path: Path) -> None:
    guide = tmp_path / "guide.txt"
    guide.write_text(hand_made(guide_from_spec(spec)))
    overlay = tmp_path / "new_fields.yaml"
    code, _ = _import(guide, ROOT / "spec", "-o", str(overlay))
    assert code == 0 and "actual_tcp_jerk" in overlay.read_text()
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "rtde_spec.cli",
            "--extra-fields",
            str(overlay),
            "fields",
            "--controller",
            "5.30.0",
            "--json",
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        check=True,
    )
    names = {f["name"]: f for f in json.loads(result.stdout)}
    jerk = names["actual_tcp_jerk"]
    assert jerk["sources"] == ["e-series-guide"] and jerk["size"] == 48


def test_fields_diff_between_versions(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fields", "--diff", "5.10", "5.11", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rtde_outputs"]["added"] == [
        {
            "name": "payload_inertia",
            "type": "VECTOR6D",
            "since": {"cb3": "3.15.0", "e-series": "5.11.0", "polyscope-x": "10.0.0"},
        }
    ]
    assert out["rtde_inputs"] == {"added": [], "removed": []} and out["rtde_outputs"]["removed"] == []
    assert out["primary"] == {"added": [], "removed": []} and out["same_line"]
    assert main(["fields", "--diff", "3.14", "5.11"]) == 0
    text = capsys.readouterr().out
    assert "3.14.0 (CB3 (PolyScope 3.x)) -> 5.11.0 (e-Series (PolyScope 5.x))" in text
    assert "different product lines" in text and "actual_current_window" in text


def test_fields_primary_answers_which_firmware_added_a_field(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fields", "--primary", "--json"]) == 0
    rows = {f"{r['message']}.{r['name']}": r for r in json.loads(capsys.readouterr().out)}
    assert rows["robot_state/cumulative_runtime_data.robot_energy_consumed_wh"]["since"] == {
        "e-series": "5.23.0",
        "polyscope-x": "10.11.0",
    }
    assert rows["robot_state/robot_mode_data.target_speed_fraction_limit"]["since"]["cb3"] == "3.2.0"
    assert "robot_state/joint_data.joints.q_actual" in rows
    assert main(["fields", "--primary", "--controller", "5.22.0"]) == 0
    assert "robot_energy_consumed_wh" not in capsys.readouterr().out


def test_an_installed_package_compares_with_its_own_spec_and_writes_an_overlay(
    spec: Spec, tmp_path: Path
) -> None:
    """Outside a checkout (no ./spec): the report and -o against the package's built-in spec;
    --write, which edits a spec folder, says what to do instead."""
    guide = tmp_path / "guide.txt"
    guide.write_text(hand_made(guide_from_spec(spec)))
    command = [sys.executable, "-m", "rtde_spec.cli", "spec", "import", str(guide)]
    result = subprocess.run(
        [*command, "--json", "-o", "new.yaml"], capture_output=True, text=True, cwd=tmp_path
    )
    assert result.returncode == 0, result.stderr
    assert [a["field"] for a in json.loads(result.stdout)["added"]] == ["actual_tcp_jerk"]
    cli = [sys.executable, "-m", "rtde_spec.cli"]
    fields = subprocess.run(
        [*cli, "--extra-fields", "new.yaml", "fields", "--controller", "5.30.0"],
        capture_output=True, text=True, cwd=tmp_path,
    )  # fmt: skip
    assert fields.returncode == 0 and "actual_tcp_jerk" in fields.stdout
    refused = subprocess.run([*command, "--write"], capture_output=True, text=True, cwd=tmp_path)
    assert refused.returncode == 2 and "-o FILE" in refused.stderr
