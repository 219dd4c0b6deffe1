"""spec import: every form of UR's documents is read, and today's spec re-imports them clean."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rtde_spec.cli.main import main
from rtde_spec.importers import detect_format, read_document
from rtde_spec.importers.diff import diff_fields
from rtde_spec.importers.primary_diff import diff_primary
from rtde_spec.metamodel.loader import load_spec

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(__file__).parent / "data" / "import"
SEEDS = Path(__file__).resolve().parents[2] / "shared" / "seeds"
SEED_FILES = [
    "rtde-guide-cb3-era.txt",
    "rtde-guide-e-series-era.txt",
    "universal-robot-rust-crate-readme.md",
    "primary-secondary-interfaces.txt",
]
needs_seeds = pytest.mark.skipif(not SEEDS.is_dir(), reason="../shared/seeds is not beside this checkout")


@pytest.fixture(scope="module")
def spec():  # type: ignore[no-untyped-def]
    return load_spec(ROOT / "spec")


def _rows(doc):  # type: ignore[no-untyped-def]
    return {(f.direction, f.name): f for f in doc.fields}


@pytest.mark.parametrize(
    ("name", "form"),
    [
        ("cb3_guide.txt", "cb3-text"),
        ("eseries_guide.txt", "e-series-text"),
        ("crate_readme.md", "markdown"),
        ("guide.html", "html"),
        ("primary_interfaces.txt", "primary-text"),
    ],
)
def test_the_form_is_detected_from_the_content(name: str, form: str) -> None:
    assert detect_format((DATA / name).read_text(encoding="utf-8")) == form


def test_cb3_text_tabs_ranges_and_short_versions(spec) -> None:  # type: ignore[no-untyped-def]
    doc = read_document(DATA / "cb3_guide.txt", spec)
    rows = _rows(doc)
    assert (doc.source, doc.line) == ("cb3-guide", "cb3")
    reg = rows["input", "input_int_register_{X}"]
    assert reg.index == (0, 47) and reg.line == 8
    assert [(n.span, n.versions) for n in reg.notes] == [
        ((0, 23), {"cb3": "3.4.0"}),
        ((24, 47), {"cb3": "3.9.0", "e-series": "5.3.0"}),
    ]
    assert rows["input", "external_force_torque"].notes[0].versions == {"cb3": "3.3.0"}  # "3.3"
    assert rows["output", "output_bit_register_{X}"].index == (64, 127)  # from "(X=[64 .. 127])"
    assert rows["output", "ft_raw_wrench"].notes[0].versions == {"e-series": "5.9.0"}
    assert ("output", "BOOL") not in rows  # the data types table is no field table


def test_eseries_text_cells_one_per_line_with_their_quirks(spec) -> None:  # type: ignore[no-untyped-def]
    doc = read_document(DATA / "eseries_guide.txt", spec)
    rows = _rows(doc)
    assert rows["output", "robot_mode"].doc == "" and rows["output", "robot_mode"].type == "INT32"  # "||"
    assert rows["output", "safety_status"].notes[0].versions == {"e-series": "5.4.0"}  # in the comment cell
    bits = rows["output", "safety_status_bits"]
    assert bits.notes[0].versions == {"e-series": "5.25.0", "polyscope-x": "10.12.0"}
    assert "Is 3PE input active" in bits.doc  # the text after the version is kept
    assert rows["input", "input_double_register_{X}"].notes[0].span == (24, 47)
    assert rows["input", "external_force_torque"].line == 16  # cut short by the table's end
    assert ("output", "Other") not in rows and len(doc.fields) == 7


def test_markdown_rust_types_and_versions_in_comments(spec) -> None:  # type: ignore[no-untyped-def]
    doc = read_document(DATA / "crate_readme.md", spec)
    rows = _rows(doc)
    assert doc.source == "crate-readme"
    assert rows["input", "speed_slider_mask"].type == "UINT32"
    assert rows["output", "joint_mode"].type == "VECTOR6INT32"
    assert rows["input", "input_bit_register_{X}"].type == "BOOL"
    read_back = rows["output", "input_int_register_{X}"]
    assert read_back.index == (0, 48) and read_back.notes[0].versions == {"cb3": "3.9.0", "e-series": "5.3.0"}
    assert rows["output", "tool_output_mode"].notes[0].versions == {"e-series": "5.2.0"}


def test_html_tables_with_an_html_parser(spec) -> None:  # type: ignore[no-untyped-def]
    doc = read_document(DATA / "guide.html", spec)
    rows = _rows(doc)
    assert rows["output", "payload_inertia"].doc == "Payload inertia matrix & elements"  # entities decoded
    assert rows["output", "payload_inertia"].line == 16  # unclosed <td>s still end at the next cell
    assert rows["output", "target_gravity"].doc == "Currently active gravity [m/s²]"
    assert rows["input", "input_int_register_{X}"].index == (0, 47)
    assert doc.line == "e-series"
    changes = diff_fields(doc, spec)  # a part of the guide: what it leaves out is all it differs in
    assert changes and {c.kind for c in changes} == {"removed"}
    assert "payload_inertia" not in {c.field for c in changes}


def test_primary_document_groups_prefixes_and_versions(spec) -> None:  # type: ignore[no-untyped-def]
    doc = read_document(DATA / "primary_interfaces.txt", spec)
    cart, joints, key = doc.members
    assert (cart.family_type, cart.member_type, joints.member_type, key.family_type, key.member_type) == (
        16,
        4,
        1,
        20,
        7,
    )
    assert [f.group for f in joints.fields] == ["repeat 6", "repeat 6"]
    assert [(f.name, f.type) for f in key.fields] == [
        ("robotMessageCode", "uint32"),
        ("robotMessageTitle", "string(uint8)"),  # the length row and the text are one field
        ("keyTextMessage", "string(uint16)"),
    ]
    changes = diff_primary(doc, spec)
    added = [(c.field, c.new, c.extra["row"].versions) for c in changes if c.kind == "added"]
    assert added == [("tcpJerk", "double", {"e-series": "5.30.0", "polyscope-x": "10.15.0"})]
    removed = {c.field for c in changes if c.kind == "removed"}
    assert {"y", "tcp_offset_x", "joints.q_target", "robot_message_argument"} <= removed
    assert not [c for c in changes if c.kind == "changed"]  # camelCase == snake_case, types agree


@needs_seeds
@pytest.mark.parametrize("name", SEED_FILES)
def test_each_seed_reimports_clean(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(
        ["spec", "import", str(SEEDS / name), "--spec-dir", str(ROOT / "spec"), "--json", "--show-known"]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert (out["added"], out["removed"], out["changed"]) == ([], [], [])
    for known in out["known"]:  # every suppressed difference names its decision and sources
        assert known["known"]["decision"] and known["known"]["sources"]


@needs_seeds
def test_seed_conflicts_are_shown_with_show_known(capsys: pytest.CaptureFixture[str]) -> None:
    main(
        [
            "spec",
            "import",
            str(SEEDS / "rtde-guide-cb3-era.txt"),
            "--spec-dir",
            str(ROOT / "spec"),
            "--show-known",
        ]
    )
    out = capsys.readouterr().out
    assert "input_int_register_{X}" in out and "[0, 48]" in out and "The CB3 guide" in out
    assert "tcp_offset" in out and "URSim 3.14.3 serves it" in out  # the CB3 line from URCL's CI
    assert "0 added, 0 removed, 0 changed; 3 known conflicts" in out


@needs_seeds
def test_importing_the_full_eseries_guide_takes_under_a_second(spec) -> None:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    doc = read_document(SEEDS / "rtde-guide-e-series-era.txt", spec)
    changes = diff_fields(doc, spec)
    elapsed = time.perf_counter() - start
    assert len(doc.fields) == 106 and all(c.known is not None for c in changes)
    assert elapsed < 1.0, elapsed


def test_a_document_of_no_known_form_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("just some text\n")
    assert main(["spec", "import", str(path), "--spec-dir", str(ROOT / "spec")]) == 2
    err = capsys.readouterr().err
    assert "cannot tell the document's form" in err
    assert str(path) in err  # which file: the error named none


def test_help_does_not_import_the_importer_or_ruamel() -> None:
    code = (
        "import sys\n"
        "from rtde_spec.cli.main import build_parser\n"
        "build_parser().format_help()\n"
        "print([m for m in sys.modules if m.startswith(('ruamel', 'rtde_spec.importers'))])\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"
