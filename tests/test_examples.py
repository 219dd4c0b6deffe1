"""`rtde-spec examples DIR`: the files the README's commands name, shipped in the package.

The shipped copies are what tests/docs_workspace.py makes (captures written with dpkt,
not our encoders); regenerate with `PYTHONPATH=. python3 -m tests.docs_workspace`.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.cli.examples_cmd import shipped
from rtde_spec.cli.main import main

from .docs_blocks import ROOT, blocks
from .docs_workspace import SHIPPED, make_workspace

GUIDE = "rtde-guide-5.30.txt"  # made from today's spec: checked by importing it, below


def test_the_shipped_files_are_what_the_generator_makes(tmp_path: Path) -> None:
    made = make_workspace(tmp_path)
    names = sorted(str(p.relative_to(made)) for p in made.rglob("*") if p.is_file())
    assert [name for name, _ in shipped()] == names
    for name in names:
        if name != GUIDE:
            assert (SHIPPED / name).read_bytes() == (made / name).read_bytes(), f"regenerate {name}"


def test_examples_writes_every_file_and_the_captures_decode(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["examples", str(tmp_path / "ex")]) == 0
    assert "wrote 13 example files" in capsys.readouterr().out
    for name, _ in shipped():
        assert (tmp_path / "ex" / name).is_file()
    tables = capture_tables(tmp_path / "ex" / "robot.pcapng")
    assert tables["rtde_outputs_1"].num_rows == 500
    assert "urcl_reverse" in capture_tables(tmp_path / "ex" / "driver.pcap")


def test_examples_never_overwrites_without_force(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "move.script").write_text("mine\n")
    assert main(["examples", "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "1 example file already there (move.script)" in err and "--force" in err
    assert (tmp_path / "move.script").read_text() == "mine\n"
    assert main(["examples", str(tmp_path), "--force"]) == 0
    assert (tmp_path / "move.script").read_text() != "mine\n"


def test_examples_refuses_a_file_for_the_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "afile").write_text("x")
    assert main(["examples", str(tmp_path / "afile")]) == 2
    assert f"{tmp_path / 'afile'}: is a file, not a folder" in capsys.readouterr().err


def test_the_guide_excerpt_is_newer_than_the_spec(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["spec", "import", str(SHIPPED / GUIDE), "--json"]) == 0
    assert '"actual_tcp_jerk"' in capsys.readouterr().out


def test_the_readme_shows_the_shipped_scenario() -> None:
    (block,) = [b for b in blocks(ROOT / "README.md") if b.language == "yaml" and "controller:" in b.text]
    assert block.text == (SHIPPED / "moving.yaml").read_text()


def test_every_input_file_the_readme_names_is_shipped() -> None:
    text = "".join(b.text for b in blocks(ROOT / "README.md") if b.language in ("sh", "python"))
    named = set(re.findall(r"\b([\w/-]+\.(?:pcapng|pcap|bin|xml|script))\b", text))
    shipped_names = {name for name, _ in shipped()}
    assert named and named <= shipped_names
    for name in ("outputs.txt", "moving.yaml", GUIDE):
        assert name in text and name in shipped_names


def test_the_spec_format_lists_every_spec_file() -> None:
    text = (ROOT / "docs" / "spec-format.md").read_text()
    files = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "spec").rglob("*.yaml"))
    assert files and [f for f in files if f not in text] == []
    for word in ("repeat:", "when:", "switch:", "length: rest", "count: N", "scale:"):
        assert word in text, f"docs/spec-format.md: the layout language's {word}"


def test_the_readme_says_tf_is_live_only() -> None:
    from rtde_spec.output import mcap

    text = (ROOT / "README.md").read_text()
    assert '"/tf"' not in Path(mcap.__file__).read_text()  # the MCAP writer has no /tf channel...
    assert "in the live view only (`--foxglove`; a recorded `.mcap` has no `/tf`)" in text  # ...and says so
