"""What a non-editable install ships: every package and the example data the demo reads."""

from __future__ import annotations

import re
import subprocess
import sys
import zipfile
from fnmatch import fnmatch
from importlib import resources
from pathlib import Path

import pytest
import setuptools

from .helpers import ROOT


def test_every_package_is_found_by_setuptools() -> None:
    found = set(setuptools.find_packages(where=str(ROOT), include=["rtde_spec*"]))
    on_disk = {
        ".".join(p.relative_to(ROOT).parts[:-1])
        for p in (ROOT / "rtde_spec").rglob("*.py")
        if "__pycache__" not in p.parts
    }
    assert on_disk <= found, on_disk - found


def test_examples_are_package_data() -> None:
    # tomllib is 3.11+; the package supports 3.10, so read the one line by pattern
    text = (ROOT / "pyproject.toml").read_text()
    match = re.search(r"^\[tool\.setuptools\.package-data\]\s*\nrtde_spec = \[(.*)\]$", text, re.M)
    assert match, "package-data for rtde_spec is missing"
    patterns = re.findall(r'"([^"]+)"', match.group(1))
    examples = resources.files("rtde_spec.examples")
    shipped = [p.name for p in examples.iterdir() if p.name != "__init__.py" and not p.name.startswith("__")]
    assert shipped
    for name in shipped:
        assert any(fnmatch(f"examples/{name}", pattern) for pattern in patterns), name


@pytest.mark.slow  # long end to end: CI runs it (RTDE_SPEC_SLOW=1), the fast loop does not
def test_wheel_ships_the_license_without_deprecation_warnings(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(tmp_path), str(ROOT)],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    assert "deprecated" not in (result.stdout + result.stderr).lower()
    (wheel,) = tmp_path.glob("rtde_spec-*.whl")
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        (metadata,) = [n for n in names if n.endswith(".dist-info/METADATA")]
        text = archive.read(metadata).decode()
    assert any(n.endswith("LICENSE") and ".dist-info/" in n for n in names), names
    assert "License-Expression: MIT" in text
