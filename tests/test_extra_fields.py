"""Fields of a newer controller from an extra YAML file, without regenerating."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from rtde_spec.errors import SpecError
from rtde_spec.metamodel.catalogue import Catalogue

EXTRA = """\
outputs:
  - name: actual_tcp_jerk
    type: VECTOR6D
    unit: m/s³
    doc: TCP jerk (a field of a future release)
    since: {e-series: 5.30.0, polyscope-x: 10.15.0}
    sources: [user]
inputs:
  - name: user_register_{X}
    type: INT32
    index: [0, 3]
    doc: Made-up input family
"""


def test_extra_file_adds_fields(tmp_path: Path) -> None:
    path = tmp_path / "extra.yaml"
    path.write_text(EXTRA)
    cat = Catalogue.builtin().with_extra(path)
    info = cat.get("actual_tcp_jerk", "output")
    assert info is not None and info.size == 48
    assert cat.available(info, "5.30.0") and not cat.available(info, "5.29.0")
    assert [n for n in cat.names("input") if n.startswith("user_register_")] == [
        f"user_register_{i}" for i in range(4)
    ]
    assert Catalogue.builtin().get("actual_tcp_jerk", "output") is None  # builtin untouched


def test_extra_file_cannot_redefine_a_builtin(tmp_path: Path) -> None:
    path = tmp_path / "extra.yaml"
    path.write_text("outputs:\n  - name: actual_q\n    type: VECTOR6D\n")
    with pytest.raises(SpecError, match="duplicate name 'actual_q'") as info:
        Catalogue.builtin().with_extra(path)
    assert info.value.issues[0].file == str(path)


def test_extra_file_is_linted(tmp_path: Path) -> None:
    path = tmp_path / "extra.yaml"
    path.write_text("outputs:\n  - name: x\n    type: DOUBEL\n    colour: red\n")
    with pytest.raises(SpecError) as info:
        Catalogue.builtin().with_extra(path)
    assert "unknown key 'colour'" in str(info.value)


def test_cli_and_environment_take_extra_files(tmp_path: Path) -> None:
    path = tmp_path / "extra.yaml"
    path.write_text(EXTRA)
    cmd = [sys.executable, "-m", "rtde_spec.cli", "fields", "--json", "--direction", "output"]
    by_flag = subprocess.run(
        [*cmd[:3], "--extra-fields", str(path), *cmd[3:]],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "actual_tcp_jerk" in {f["name"] for f in json.loads(by_flag.stdout)}
    env = {**os.environ, "RTDE_SPEC_EXTRA_FIELDS": str(path)}
    by_env = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env)
    assert "actual_tcp_jerk" in {f["name"] for f in json.loads(by_env.stdout)}
