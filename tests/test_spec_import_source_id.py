"""spec import --source is checked against the spec's source-id pattern before anything is read.

`--source 'a b/c'` was accepted: the diff ran (recorded conflicts never matching it) and --write
failed only when the checked copy of the spec did not validate.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.test_spec_import_safety import ROOT, _cli, _doc


@pytest.mark.parametrize("source", ["a b/c", "Upper", "-lead", "x_y", ""])
def test_a_source_id_the_spec_cannot_record_is_refused_up_front(tmp_path: Path, source: str) -> None:
    tree = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", tree)
    before = (tree / "rtde/fields.yaml").read_bytes()
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Jerk | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), f"--source={source}", "--write")
    assert result.returncode == 2, result.stderr
    assert f"--source {source!r}: a source id is" in result.stderr
    assert "^[a-z0-9][a-z0-9.-]*$" in result.stderr and "Traceback" not in result.stderr
    assert (tree / "rtde/fields.yaml").read_bytes() == before


def test_a_good_source_id_is_taken(tmp_path: Path) -> None:
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Jerk | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--source", "my-guide.2024")
    assert result.returncode == 0, result.stderr
