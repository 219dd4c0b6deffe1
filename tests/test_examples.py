"""`rtde-spec examples DIR`: the files the README's commands name, shipped in the package.

The shipped copies are what tests/docs_workspace.py makes (captures written with dpkt,
not our encoders); regenerate with `PYTHONPATH=. python3 -m tests.docs_workspace`. But
`driver.pcap` is recorded: a driver-like client's session with `rtde-spec serve`, captured on
loopback by rtde_spec/examples/make_driver_capture.py; it is held here to what that session sends.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.cli.examples_cmd import shipped
from rtde_spec.cli.main import main

from .docs_blocks import ROOT, blocks
from .docs_workspace import RECORDED, SHIPPED, make_workspace

GUIDE = "rtde-guide-5.30.txt"  # made from today's spec: checked by importing it, below


def test_the_shipped_files_are_what_the_generator_makes(tmp_path: Path) -> None:
    made = make_workspace(tmp_path)
    names = sorted(str(p.relative_to(made)) for p in made.rglob("*") if p.is_file())
    assert [name for name, _ in shipped()] == names
    for name in names:
        if name not in (GUIDE, RECORDED):
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


def test_the_driver_capture_is_the_recorded_session_on_every_port_it_used() -> None:
    """What make_driver_capture's client sent and the emulator's program answered, decoded."""
    from rtde_spec.examples import make_driver_capture as drv

    path = SHIPPED / RECORDED
    assert drv.check(path) == []  # the six connections, nothing foreign, no damage
    tables = {name: table.to_pylist() for name, table in capture_tables(path).items()}
    dashboard = [(row["request"], row["outcome"]) for row in tables["dashboard"] if row["request"]]
    assert dashboard == [(command, "ok") for command in drv.DASHBOARD]
    servo = tables["urcl_reverse"]
    assert [row["control_mode"] for row in servo] == [1] * (drv.SERVO_STEPS + 1) + [-2]
    assert [servo[0][f"target_{j}"] for j in range(6)] == list(drv.HOME)
    points = tables["urcl_trajectory_points"]
    assert [[p[f"target_{j}"] for j in range(6)] for p in points] == [list(t[0]) for t in drv.TRAJECTORY]
    assert [(p["velocity"], p["acceleration"], p["duration"]) for p in points] == [
        (v, a, t) for _, v, a, t, _ in drv.TRAJECTORY
    ]
    start = tables["urcl_reverse_trajectory"][0]
    assert (start["trajectory_action"], start["point_count"]) == (1, len(drv.TRAJECTORY))
    assert [row["result"] for row in tables["urcl_trajectory_results"]] == [0]  # the robot's answer
    assert [row["variant"] for row in tables["urcl_script_commands"]] == ["set_payload", "zero_ft_sensor"]
    texts = [row["text_message"] for row in tables["primary_text_message"]]
    assert "trajectory done" in texts and texts[-1] == "external control stopped"  # the program ran
    (script,) = tables["primary_scripts"]  # headless mode: the program went to 30001
    ports = {"driver": "127.0.0.1", "reverse": 50001, "trajectory": 50003, "script_command": 50004}
    assert script["script"] == drv.PROGRAM.format(**ports)  # rtde_spec/examples/external_control.script
    assert len(tables["rtde_outputs_1"]) > 100 and tables["rtde_inputs_1"][0]["speed_slider_fraction"] == 1.0


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
