"""One set of conventions over every subcommand's parser (docs/cli.md has the table).

Walks the real parser of `rtde-spec`, so a new subcommand or option is held to them too.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from rtde_spec.cli.conventions import leaf_parsers, plural
from rtde_spec.cli.main import build_parser, main

LEAVES = leaf_parsers(build_parser())
IDS = [words for words, _ in LEAVES]
OUTPUT_FORMATS = {"table", "text", "csv", "parquet", "jsonl", "json", "mcap"}
RETIRED = {"--out", "--outdir", "--overlay", "--dir"}  # spellings of -o/--output kept as hidden aliases
DEPRECATED = {  # subcommand: old spellings users may rely on, still accepted, not shown
    "capture": {"--outdir"},
    "demo": {"--out"},
    "spec import": {"--overlay"},
    "wireshark": {"--dir"},
    "validate": {"--format"},
    "watch": {"--json"},
}


def visible(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if a.help != argparse.SUPPRESS and a.option_strings]


def hidden(parser: argparse.ArgumentParser) -> set[str]:
    return {s for a in parser._actions if a.help == argparse.SUPPRESS for s in a.option_strings}


def test_every_subcommand_is_checked() -> None:
    assert {"capture", "decode", "demo", "examples", "fields", "plot", "record", "serve", "spec import",
            "validate", "watch", "wireshark"} <= set(IDS)  # fmt: skip


@pytest.mark.parametrize(("words", "parser"), LEAVES, ids=IDS)
def test_help_has_one_paragraph_and_two_to_four_examples(words: str, parser: argparse.ArgumentParser) -> None:
    description = parser.description or ""
    assert 40 <= len(description) <= 700, f"{words}: a one-paragraph description ({len(description)} chars)"
    assert "\n\n" not in description.strip(), f"{words}: one paragraph"
    epilog = parser.epilog or ""
    examples = [line for line in epilog.splitlines() if line.startswith("  rtde-spec ")]
    assert epilog.startswith("examples:") and 2 <= len(examples) <= 4, f"{words}: 2-4 examples"
    assert all(f"rtde-spec {words}" in line for line in examples), examples
    assert "examples:" in parser.format_help()


@pytest.mark.parametrize(("words", "parser"), LEAVES, ids=IDS)
def test_outputs_are_o_output(words: str, parser: argparse.ArgumentParser) -> None:
    shown = {s for a in visible(parser) for s in a.option_strings}
    assert not shown & RETIRED, f"{words}: use -o/--output, not {shown & RETIRED}"
    if "-o" in shown:
        assert parser._option_string_actions["-o"] is parser._option_string_actions["--output"]


@pytest.mark.parametrize(("words", "parser"), LEAVES, ids=IDS)
def test_format_is_for_outputs_and_json_is_one_document(words: str, parser: argparse.ArgumentParser) -> None:
    actions = {s: a for a in visible(parser) for s in a.option_strings}
    if "--format" in actions:
        assert set(actions["--format"].choices or ()) <= OUTPUT_FORMATS, f"{words}: --input-format for inputs"
    if "--json" in actions:
        assert "line" not in (actions["--json"].help or "").lower(), f"{words}: a stream is --jsonl"


@pytest.mark.parametrize(("words", "parser"), LEAVES, ids=IDS)
def test_options_taking_a_value_name_it(words: str, parser: argparse.ArgumentParser) -> None:
    for action in visible(parser):
        if action.nargs == 0 or action.choices is not None:
            continue
        assert action.metavar is not None, (
            f"{words} {action.option_strings[-1]}: give a metavar naming the unit"
        )
        metavars = action.metavar if isinstance(action.metavar, tuple) else (action.metavar,)
        for metavar in metavars:
            assert metavar != action.dest.upper() or metavar in ("PORT", "HOST", "SECONDS"), (
                f"{words} {action.option_strings[-1]}: {metavar} is the option's name, not its unit"
            )


@pytest.mark.parametrize(("words", "parser"), LEAVES, ids=IDS)
def test_global_options_are_accepted_after_the_subcommand(
    words: str, parser: argparse.ArgumentParser
) -> None:
    assert {"--debug", "--extra-fields"} <= set(parser._option_string_actions)


@pytest.mark.parametrize(("words", "old"), [(w, o) for w, olds in DEPRECATED.items() for o in olds])
def test_old_spellings_stay_as_hidden_aliases(words: str, old: str) -> None:
    (parser,) = [p for w, p in LEAVES if w == words]
    assert old in hidden(parser)


def test_extra_fields_after_the_subcommand(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    extra = tmp_path / "x.yaml"
    extra.write_text("outputs:\n  - name: my_new_output\n    type: DOUBLE\n    since: {e-series: 5.25.0}\n")
    assert main(["fields", "--controller", "5.25.0", "--extra-fields", str(extra), "--json"]) == 0
    assert "my_new_output" in capsys.readouterr().out


def test_plurals() -> None:
    assert [plural(n, "connection") for n in (0, 1, 2)] == ["0 connections", "1 connection", "2 connections"]


def test_the_docs_table_names_every_subcommand() -> None:
    text = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    for words in IDS:
        assert f"`{words}`" in text, f"docs/cli.md: add {words}"
