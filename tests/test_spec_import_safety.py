"""spec import --write and -o cannot damage the spec: checked copy first, atomic replace, modes kept,
removals only when asked, overlays that load with --extra-fields."""

from __future__ import annotations

import difflib
import json
import os
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
HEAD = "## Robot Controller Outputs\n\n| Name | Type | Comment | Introduced in version |\n|---|---|---|---|\n"


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "rtde_spec.cli", *args], capture_output=True, text=True, cwd=ROOT, timeout=300
    )


@pytest.fixture
def tree(tmp_path: Path) -> Path:
    spec = tmp_path / "spec"
    shutil.copytree(ROOT / "spec", spec)
    return spec


def _doc(tmp_path: Path, rows: str, placeholder: bool = True) -> Path:
    path = tmp_path / "guide.md"
    path.write_text(HEAD + rows + ("| … and more fields … | | | |\n" if placeholder else ""))
    return path


def test_write_keeps_mode_and_touches_only_what_changed(tree: Path, tmp_path: Path) -> None:
    fields = tree / "rtde/fields.yaml"
    os.chmod(fields, 0o644)
    before = fields.read_text()
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0, result.stderr
    assert "wrote 1 of 1 changes" in result.stderr
    assert stat.S_IMODE(fields.stat().st_mode) == 0o644  # was 0600 after the temp-file rename
    diff = [d for d in difflib.ndiff(before.splitlines(), fields.read_text().splitlines()) if d[:1] in "+-"]
    assert diff and all(d.startswith("+ ") for d in diff), diff  # nothing else edited or lost
    assert any("actual_tcp_jerk" in d for d in diff)
    assert not list(tree.rglob(".fields.yaml.*"))  # no temp file left


def test_a_read_only_spec_file_is_refused(tree: Path, tmp_path: Path) -> None:
    fields = tree / "rtde/fields.yaml"
    os.chmod(fields, 0o444)
    before = fields.read_bytes()
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 2 and "read-only" in result.stderr
    assert fields.read_bytes() == before


def test_an_edit_that_would_break_the_spec_writes_nothing(tree: Path, tmp_path: Path) -> None:
    fields = tree / "rtde/fields.yaml"
    before = fields.read_bytes()
    doc = _doc(tmp_path, "| mystery_field | QUATERNION | A type no spec knows | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 2, result.stderr
    assert "would leave a spec that does not load" in result.stderr and "QUATERNION" in result.stderr
    assert "Traceback" not in result.stderr
    assert fields.read_bytes() == before


def test_many_removals_are_refused_without_allow_removals(tree: Path, tmp_path: Path) -> None:
    fields = tree / "rtde/fields.yaml"
    before = fields.read_bytes()
    rows = "| timestamp | DOUBLE | Time elapsed since the controller was started [s] | |\n"
    doc = _doc(tmp_path, rows, placeholder=False)  # a 2-row table that claims to be the whole list
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 2 and "would remove" in result.stderr and "--allow-removals" in result.stderr
    assert fields.read_bytes() == before
    # with a placeholder row the table says it stops early: nothing is removed, the rest is written
    doc = _doc(tmp_path, rows)
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0 and "wrote 0 of 0 changes" in result.stderr


def test_overlay_loads_with_extra_fields_and_has_an_ordinary_mode(tmp_path: Path) -> None:
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    overlay = tmp_path / "overlay.yaml"
    result = _cli("spec", "import", str(doc), "--spec-dir", str(ROOT / "spec"), "-o", str(overlay))
    assert result.returncode == 0, result.stderr
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(overlay.stat().st_mode) == 0o666 & ~mask
    listed = _cli("--extra-fields", str(overlay), "fields", "--controller", "5.30.0", "--json")
    assert listed.returncode == 0, listed.stderr
    names = {f["name"] for f in json.loads(listed.stdout)}
    assert "actual_tcp_jerk" in names


def test_a_full_temporary_folder_is_said_in_a_line_and_the_spec_stays(tree: Path, tmp_path: Path) -> None:
    """The checked copy goes to TMPDIR first; on a full one, shutil's error listed every file it
    could not copy (2 kB of a list's repr). Now one line names the folder and why, exit 1."""
    from tests.faults.tmpfs import fill, mounted_tmpfs

    small = tmp_path / "tmp"
    small.mkdir()
    fields = tree / "rtde/fields.yaml"
    before = fields.read_bytes()
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    with mounted_tmpfs(small, "size=256k"):
        fill(small, 16_000)  # room for tempfile's own probe of the folder, not for the spec
        argv = [sys.executable, "-m", "rtde_spec.cli", "spec", "import", str(doc), "--spec-dir", str(tree)]
        result = subprocess.run(
            [*argv, "--write"],
            capture_output=True, text=True, cwd=ROOT, timeout=300, env={**os.environ, "TMPDIR": str(small)},
        )  # fmt: skip
    assert result.returncode == 1, result.stderr
    error = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(error) == 1 and len(error[0]) < 400, result.stderr
    assert "could not be copied there to be checked, so nothing was written" in error[0], error
    assert "the disk is full" in error[0] and "temporary folder" in error[0], error
    assert fields.read_bytes() == before


def test_an_overlay_never_replaces_a_spec_file_or_the_document(tree: Path, tmp_path: Path) -> None:
    """-o spec/rtde/fields.yaml replaced the spec's 900-line field list with the 7-line overlay."""
    fields = tree / "rtde/fields.yaml"
    before = fields.read_bytes()
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "-o", str(fields))
    assert result.returncode == 2 and "is a file of the spec" in result.stderr, result.stderr
    assert fields.read_bytes() == before
    text = doc.read_bytes()
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "-o", str(doc))
    assert result.returncode == 2 and "is the document being imported" in result.stderr, result.stderr
    assert doc.read_bytes() == text
    new = tree / "rtde/new_fields.yaml"  # a new file beside the spec's own ones is no harm: written
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "-o", str(new))
    assert result.returncode == 0 and "actual_tcp_jerk" in new.read_text(), result.stderr


def test_a_value_the_spec_decided_against_is_never_written_under_another_id(
    tree: Path, tmp_path: Path
) -> None:
    """A recorded conflict matches only its own document's id, and a copy's id comes from its file name:
    the crate README saved as README.md wrote back 14 values the spec had decided against."""
    from rtde_spec.metamodel.loader import load_spec

    spec = load_spec(ROOT / "spec")
    entry, conflict = next(
        (e, c)
        for e in spec.fields.outputs
        for c in e.conflicts
        if c.what == "description" and c.document and e.index is None
    )
    fields = tree / "rtde/fields.yaml"
    before = fields.read_bytes()
    doc = _doc(tmp_path, f"| {entry.name} | {entry.type} | {conflict.document} | |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0, result.stderr
    assert f"not written: {entry.name} (output) description" in result.stderr, result.stderr
    assert "wrote 0 of 1 changes" in result.stderr and "--source names the document" in result.stdout
    assert fields.read_bytes() == before
    result = _cli(
        "spec", "import", str(doc), "--spec-dir", str(tree), "--source", conflict.sources[0], "--check"
    )
    assert result.returncode == 0 and "0 changed; 1 known conflicts" in result.stdout, result.stdout


@pytest.mark.parametrize("form", ["crlf", "bom"])
def test_a_windows_checkouts_spec_file_keeps_its_line_ends(tree: Path, tmp_path: Path, form: str) -> None:
    """git's core.autocrlf gives fields.yaml CRLF line ends: --write rewrote every line to LF."""
    fields = tree / "rtde/fields.yaml"
    text = fields.read_bytes()
    before = text.replace(b"\n", b"\r\n") if form == "crlf" else b"\xef\xbb\xbf" + text
    fields.write_bytes(before)
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0 and "wrote 1 of 1 changes" in result.stderr, result.stderr
    after = fields.read_bytes()
    assert after.startswith(before[:3])
    end = b"\r\n" if form == "crlf" else b"\n"
    old, new = before.split(end), after.split(end)
    diff = [d for d in difflib.ndiff(old, new) if d[:1] in "+-"]
    assert diff and all(d.startswith("+ ") for d in diff), diff[:5]  # only the new entry's lines
    assert (b"\r" in after) == (form == "crlf") and b"\r\r" not in after


def test_a_primary_change_write_cannot_make_is_said_with_why(tree: Path, tmp_path: Path) -> None:
    """'wrote 0 of 1 changes' alone: a joint's type changed inside its repeat is a layout decision."""
    interface = tree / "primary/interface.yaml"
    before = interface.read_bytes()
    joint = ["double q_actual", "double q_target", "double qd_actual", "float I_actual", "double V_actual"]
    joint += ["float T_motor", "float T_micro", "uint8_t jointMode"]
    head = ["Robot Software 5.9", "Joint Data (Sub Package of Robot State Message)", "Field", "Description"]
    rows = ["uint32_t packageSize", "uint8_t packageType", "ROBOT_STATE_PACKAGE_TYPE_JOINT_DATA = 1"]
    rows += ["Following 8 fields are repeated for each joint (6 times)", *(f"\u2192 {r}" for r in joint)]
    doc = tmp_path / "primary.txt"
    doc.write_text("\n\n".join(head + rows) + "\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0, result.stderr
    assert "not written: joints.v_actual (robot_state/joint_data) type: a layout decision" in result.stderr
    assert interface.read_bytes() == before


def test_rows_run_together_by_expanded_tabs_are_never_written(tree: Path, tmp_path: Path) -> None:
    """A tab copy whose tabs an editor expanded to spaces reads as columns that are not there: a row
    runs into the one above (actual_q gets its version and words) and nothing said so; --write was
    refused only when the lost rows made more than five removals."""
    rows = [
        ("timestamp", "DOUBLE", "Time elapsed since the controller was started [s]", ""),
        ("target_q", "VECTOR6D", "Target joint positions", ""),
        ("actual_q", "VECTOR6D", "Actual joint positions", ""),
        ("actual_TCP_acceleration", "VECTOR3D", "Actual TCP acceleration", "5.23.0 / 10.11.0"),
        ("actual_qd", "VECTOR6D", "Actual joint velocities", ""),
    ]
    lines = ["Robot Controller Outputs", "Name\tType\tComment\tIntroduced in version"]
    lines += ["\t".join(r) for r in rows] + ["… and more"]
    doc = tmp_path / "expanded.txt"
    doc.write_text("\n".join(line.expandtabs(4) for line in lines) + "\n")
    fields = tree / "rtde/fields.yaml"
    before = fields.read_bytes()
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 2, result.stderr
    assert "the comment of actual_q holds another row ('actual_TCP_acceleration VECTOR3D')" in result.stderr
    assert fields.read_bytes() == before


@pytest.mark.parametrize("comment", ["yes", "Off"])
def test_a_comment_that_yaml_1_1_reads_as_a_bool_is_written_as_text(
    tree: Path, tmp_path: Path, comment: str
) -> None:
    """ruamel (YAML 1.2) wrote `doc: yes` unquoted; the spec's loader (YAML 1.1) read True and
    `--write` refused the import."""
    import yaml

    doc = _doc(tmp_path, f"| actual_tcp_jerk | VECTOR6D | {comment} | 5.30.0 |\n")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "--write")
    assert result.returncode == 0, result.stderr
    fields = yaml.safe_load((tree / "rtde/fields.yaml").read_text())["outputs"]
    assert [f["doc"] for f in fields if f["name"] == "actual_tcp_jerk"] == [comment]


def test_a_spec_file_is_on_disk_before_it_replaces_the_old_one(
    tree: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The write was renamed into place unsynced: a power loss right after could leave the spec
    file empty. The file and its folder are now synced (the real fsync, counted)."""
    from rtde_spec.importers import write

    synced: list[str] = []
    real = os.fsync

    def fsync(fd: int) -> None:
        synced.append(os.readlink(f"/proc/self/fd/{fd}"))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)
    target = tree / "rtde" / "fields.yaml"
    write.replace_text(target, target.read_text() + "# one more line\n")
    assert target.read_text().endswith("# one more line\n")
    assert any(".fields.yaml" in s for s in synced), synced  # the temporary file, before the rename
    assert str(target.parent) in synced, synced  # the folder, after it


def test_an_overlay_under_a_file_says_so(tree: Path, tmp_path: Path) -> None:
    """`-o afile/x.yaml` said "writing failed: File exists" (the folder made where a file is)."""
    (tmp_path / "afile").write_text("a file\n")
    doc = _doc(tmp_path, "| actual_tcp_jerk | VECTOR6D | Actual TCP jerk | 5.30.0 |\n")
    overlay = str(tmp_path / "afile" / "x.yaml")
    result = _cli("spec", "import", str(doc), "--spec-dir", str(tree), "-o", overlay)
    assert result.returncode == 1, result.stderr
    assert "a part of the path is a file, not a folder" in result.stderr, result.stderr
    assert "File exists" not in result.stderr
