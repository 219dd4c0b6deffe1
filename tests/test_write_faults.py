"""Every command's file outputs under real faults: a full disk, a read-only file system, a folder
where the file should be, a symlink in the way; and special files given as inputs.

The rules (see `rtde_spec.output.partfile`): a failed write leaves an existing file byte-identical
and no temporary file behind, names the output (never its temporary file), says why in words (no
bare `[Errno N]`) and exits 1; a symlink is written through. A pipe, a device or an empty file given
as an input is named as what it is. The full disk and the read-only file system are tmpfs mounts of
the test's own (root can mount one; CI runs as root), skipped only where this process may not.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from rtde_spec import build
from rtde_spec.cli.main import main
from rtde_spec.errors import OutputError
from rtde_spec.output.partfile import write_whole
from rtde_spec.output.tempnames import PART_MARK
from tests.faults.tmpfs import fill, mounted_tmpfs
from tests.test_cli import cli

LUA = "rtde_spec.lua"


@pytest.fixture
def disk(tmp_path: Path) -> Iterator[Path]:
    """A 2 MB tmpfs of its own, to fill with `fill`."""
    where = tmp_path / "disk"
    where.mkdir()
    with mounted_tmpfs(where, "size=2m"):
        yield where


@pytest.fixture
def read_only(tmp_path: Path) -> Iterator[Path]:
    """An empty tmpfs mounted read-only."""
    where = tmp_path / "ro"
    where.mkdir()
    with mounted_tmpfs(where, "size=64k,ro"):
        yield where


def state(folder: Path) -> dict[str, str]:
    """Every file under `folder` (hidden ones too, the filler left out) and its digest."""
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and p.name != "filler"
    }


def no_temp_files(folder: Path) -> None:
    left = [p for p in folder.rglob("*") if PART_MARK in p.name or p.name.endswith(".part")]
    assert not left, left


def said(err: str, path: Path, why: str) -> None:
    """The error names the output and says why in words, never a bare errno or a temporary file."""
    assert path.name in err, err
    assert why in err, err
    assert "Errno" not in err and ".part" not in err, err


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str]:
    code = main(list(args))
    return code, capsys.readouterr().err


@pytest.fixture(scope="module")
def guide(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A guide that adds one field (actual_tcp_jerk): `spec import -o` has an overlay to write."""
    from rtde_spec.metamodel.loader import load_spec
    from tests.test_spec_import_write import ROOT, guide_from_spec, hand_made

    path = tmp_path_factory.mktemp("guide") / "guide.txt"
    path.write_text(hand_made(guide_from_spec(load_spec(ROOT / "spec"))))
    return path


@pytest.fixture(scope="module")
def table(tmp_path_factory: pytest.TempPathFactory) -> Path:
    pytest.importorskip("matplotlib")
    path = tmp_path_factory.mktemp("table") / "t.csv"
    path.write_text("timestamp,actual_q_0,actual_q_1\n0,1,2\n0.5,2,3\n1,3,1\n")
    return path


# 1. wireshark --install


def test_wireshark_install_on_a_full_disk_keeps_the_dissector_there(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plugins = disk / "plugins"
    assert run(capsys, "wireshark", "--install", "-o", str(plugins))[0] == 0
    (plugins / LUA).write_text("-- a dissector of an earlier release\n")
    before = state(disk)
    fill(disk)
    code, err = run(capsys, "wireshark", "--install", "-o", str(plugins))
    assert code == 1, err
    said(err, plugins / LUA, "the disk is full")
    assert state(disk) == before
    no_temp_files(disk)


def test_wireshark_install_on_a_full_fresh_disk_leaves_no_file(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fill(disk, 60_000)  # the dissector is about 175 kB
    code, err = run(capsys, "wireshark", "--install", "-o", str(disk / "plugins"))
    assert code == 1, err
    said(err, disk / "plugins" / LUA, "the disk is full")
    assert not (disk / "plugins" / LUA).exists()
    no_temp_files(disk)


# 2. examples


def test_examples_on_a_full_disk_leave_no_temporary_files(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fill(disk, 100_000)  # the examples are about 380 kB
    code, err = run(capsys, "examples", str(disk / "ex"))
    assert code == 1, err
    assert "the disk is full" in err and "Errno" not in err and ".part" not in err, err
    assert str(disk / "ex") in err, err  # the file that did not fit, under the folder given
    no_temp_files(disk)


def test_examples_that_do_not_fit_write_none_and_run_again_when_there_is_room(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Half the set and an error was a folder the next run refused as "already there"."""
    (disk / "ex").mkdir()
    (disk / "ex" / "mine.txt").write_text("the user's own file\n")
    fill(disk, 100_000)  # the examples are about 380 kB
    code, err = run(capsys, "examples", str(disk / "ex"))
    assert code == 1 and "the disk is full" in err, err
    assert sorted(p.name for p in (disk / "ex").rglob("*")) == ["mine.txt"]  # no example, no subfolder
    (disk / "filler").unlink()
    assert run(capsys, "examples", str(disk / "ex"))[0] == 0  # not "already there": nothing was
    assert (disk / "ex" / "move.script").is_file() and (disk / "ex" / "mine.txt").is_file()


def test_examples_into_a_new_folder_on_a_full_disk_leave_no_folder(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fill(disk, 100_000)
    assert run(capsys, "examples", str(disk / "new" / "ex"))[0] == 1
    assert sorted(p.name for p in disk.iterdir()) == ["filler"]


def test_examples_force_on_a_full_disk_keeps_the_files_there(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run(capsys, "examples", str(disk / "ex"))[0] == 0
    before = state(disk)
    fill(disk, 30_000)
    code, err = run(capsys, "examples", str(disk / "ex"), "--force")
    assert code == 1, err
    assert "the disk is full" in err and "Errno" not in err and ".part" not in err, err
    assert state(disk) == before
    no_temp_files(disk)


# 3. plot, spec import -o and demo on a full disk


def test_plot_on_a_full_disk_names_the_image(
    disk: Path, table: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    image = disk / "p.png"
    assert run(capsys, "plot", str(table), "actual_q", "-o", str(image))[0] == 0
    before = state(disk)
    fill(disk)
    code, err = run(capsys, "plot", str(table), "actual_q", "-o", str(image))
    assert code == 1, err
    said(err, image, "the disk is full")
    assert state(disk) == before
    no_temp_files(disk)


def test_spec_import_overlay_on_a_full_disk_names_the_file(
    disk: Path, guide: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    overlay = disk / "new.yaml"
    overlay.write_text("# an overlay of an earlier import\n")
    before = state(disk)
    fill(disk)
    code, err = run(capsys, "spec", "import", str(guide), "-o", str(overlay))
    assert code == 1, err
    said(err, overlay, "the disk is full")
    assert state(disk) == before
    no_temp_files(disk)


def test_demo_whose_plot_does_not_fit_names_the_image(disk: Path, tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    out = disk / "d"
    out.mkdir()
    fill(disk, 45_000)  # the CSV of a second (about 27 kB) fits, its plot (about 38 kB) does not
    result = cli("demo", "-o", str(out), "--seconds", "1")
    assert result.returncode == 1, result.stderr
    said(result.stderr, out / "joints.png", "the disk is full")
    assert not (out / "joints.png").exists() and not (out / "joints.csv").exists()  # the pair, or none
    no_temp_files(disk)


def test_demo_whose_plot_does_not_fit_keeps_the_earlier_pair(disk: Path) -> None:
    """The new CSV went in place and the plot did not: a joints.csv of this run beside the
    joints.png of the one before. Now both stay as they were."""
    pytest.importorskip("matplotlib")
    out = disk / "d"
    assert cli("demo", "-o", str(out), "--seconds", "1").returncode == 0
    before = state(out)
    fill(disk, 45_000)
    result = cli("demo", "-o", str(out), "--seconds", "1")
    assert result.returncode == 1, result.stderr
    said(result.stderr, out / "joints.png", "the disk is full")
    assert state(out) == before
    no_temp_files(disk)


# 4. a folder in the way, a read-only file system: the output named, the reason in words


def test_save_recipes_on_a_full_disk_keeps_the_file_there(disk: Path) -> None:
    """`save_recipes` wrote in place: a full disk left the recipe file cut off."""
    from rtde_spec.recipes.files import save_recipes
    from rtde_spec.recipes.model import Recipe

    path = disk / "outputs.xml"
    save_recipes([Recipe(("timestamp", "actual_q"), key="state")], path)
    before = state(disk)
    fill(disk)
    many = Recipe(tuple(f"output_double_register_{i}" for i in range(48)) * 200, key="state")
    with pytest.raises(OutputError) as info:
        save_recipes([many], path)
    said(str(info.value), path, "the disk is full")
    assert state(disk) == before
    no_temp_files(disk)


def test_plot_and_spec_import_to_a_folder_say_so(
    tmp_path: Path, table: Path, guide: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "isdir.png"
    folder.mkdir()
    code, err = run(capsys, "plot", str(table), "actual_q", "-o", str(folder))
    assert code == 2, err
    said(err, folder, "is a directory")
    folder = tmp_path / "isdir.yaml"
    folder.mkdir()
    code, err = run(capsys, "spec", "import", str(guide), "-o", str(folder))
    assert code == 2, err
    said(err, folder, "is a directory")
    no_temp_files(tmp_path)


def test_a_read_only_file_system_is_named_for_the_output(
    read_only: Path, table: Path, guide: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for args, output in (
        (["plot", str(table), "actual_q", "-o"], read_only / "p.png"),
        (["spec", "import", str(guide), "-o"], read_only / "new.yaml"),
    ):
        code, err = run(capsys, *args, str(output))
        assert code == 1, err
        said(err, output, "read-only")
    code, err = run(capsys, "wireshark", "--install", "-o", str(read_only))
    assert code == 2, err  # a folder that cannot be written to: the -o given
    said(err, read_only / LUA, "read-only")
    with pytest.raises(OutputError, match="read-only") as caught:
        write_whole(read_only / "listing.json", b"{}\n")
    said(str(caught.value), read_only / "listing.json", "file system is read-only")


def test_a_capture_into_its_earlier_tables_on_a_file_system_made_read_only_names_the_table(
    disk: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The second run's error was "[Errno 30] Read-only file system: '.robot-....parquet.part-N'":
    removing the temporary file (never made) failed too, and its error took the place of the one
    naming the table."""
    from tests.capture_files import Conversation, write

    capture = disk.parent / "robot.pcap"
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    write(capture, [conv])
    out = disk / "out"
    assert run(capsys, "capture", str(capture), "-o", str(out), "--lenient")[0] == 0
    before = state(out)
    subprocess.run(["mount", "-o", "remount,ro", str(disk)], check=True)
    code, err = run(capsys, "capture", str(capture), "-o", str(out), "--lenient")
    assert code == 1, err
    assert "read-only" in err and "robot" in err and "Errno" not in err and ".part" not in err, err
    assert state(out) == before


# 5. special files as inputs: said what they are


@pytest.fixture
def fifo(tmp_path: Path) -> Path:
    path = tmp_path / "fifo"
    os.mkfifo(path)
    return path


def refused(result: subprocess.CompletedProcess[str], what: str) -> None:
    assert result.returncode == 2, result.stderr
    assert what in result.stderr, result.stderr
    assert "no such" not in result.stderr and "neither a file nor hex" not in result.stderr, result.stderr
    assert "unknown" not in result.stderr, result.stderr


def test_decode_names_a_pipe_or_a_device(fifo: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    refused(cli("decode", "/dev/null"), "character device")
    refused(cli("decode", str(fifo)), "FIFO")
    monkeypatch.chdir(tmp_path)  # the bare name "fifo" is no hex either
    refused(cli("decode", "fifo"), "FIFO")
    refused(cli("decode", "00045601", "--recipe", "fifo"), "FIFO")


def test_spec_import_names_a_pipe_a_device_or_an_empty_file(fifo: Path, tmp_path: Path) -> None:
    refused(cli("spec", "import", "/dev/null"), "character device")
    refused(cli("spec", "import", str(fifo)), "FIFO")
    empty = tmp_path / "empty.txt"
    empty.write_bytes(b"")
    refused(cli("spec", "import", str(empty)), "empty")


def test_a_recipe_file_that_is_a_pipe_is_refused_before_reading(fifo: Path) -> None:
    from rtde_spec.errors import RecipeError
    from rtde_spec.recipes.files import load_recipes

    with unblocked(fifo), pytest.raises(RecipeError, match="FIFO"):
        load_recipes(fifo)  # would wait for a writer if read


@contextmanager
def unblocked(fifo: Path) -> Iterator[None]:
    """A writer that opens `fifo` whenever a reader waits on it and closes it at once, so a reader
    (code that should not read it) sees an empty file instead of hanging the test."""
    done = threading.Event()

    def writer() -> None:
        while not done.is_set():
            try:
                os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
            except OSError:  # no reader yet
                pass
            done.wait(0.05)

    thread = threading.Thread(target=writer, daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()


# 6. symlinks: every command writes through, as record and decode do


def test_outputs_write_through_a_symlink(
    tmp_path: Path, table: Path, guide: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    real = tmp_path / "real"
    real.mkdir()
    for args, name in (
        (["plot", str(table), "actual_q", "-o"], "p.png"),
        (["spec", "import", str(guide), "-o"], "new.yaml"),
    ):
        (real / name).write_bytes(b"old")
        link = tmp_path / name
        link.symlink_to(real / name)
        assert run(capsys, *args, str(link))[0] == 0
        assert link.is_symlink() and (real / name).read_bytes() != b"old"
    examples = tmp_path / "ex"
    assert run(capsys, "examples", str(examples))[0] == 0
    shipped = (examples / "move.script").read_bytes()
    (real / "move.script").write_bytes(b"old")
    (examples / "move.script").unlink()
    (examples / "move.script").symlink_to(real / "move.script")
    assert run(capsys, "examples", str(examples), "--force")[0] == 0
    assert (examples / "move.script").is_symlink()
    assert (real / "move.script").read_bytes() == shipped
    no_temp_files(tmp_path)


def test_a_recipe_or_a_recipe_list_that_is_a_fifo_or_a_device_is_named_as_such(tmp_path: Path) -> None:
    """`record --recipe FIFO` said "no such recipe file"; `validate FIFO` took its name for a field."""
    import sys

    fifo = tmp_path / "names"
    os.mkfifo(fifo)
    for argv in (
        ["record", "--recipe", str(fifo), "--host", "127.0.0.9", "-o", str(tmp_path / "r.csv")],
        ["validate", str(fifo)],
        ["validate", os.devnull],
    ):
        done = subprocess.run(
            [sys.executable, "-m", "rtde_spec", *argv], capture_output=True, text=True, timeout=60
        )
        assert done.returncode == 2, (argv, done.stderr)
        assert "not a regular file" in done.stderr and ("FIFO" in done.stderr or "device" in done.stderr)


# a strict decode's fault: -o FILE is put in place only whole


@pytest.mark.parametrize("suffix", ["csv", "parquet", "jsonl"])
def test_a_decode_that_stops_at_a_fault_keeps_the_file_there(
    tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A truncated input ends a strict decode with its fault: the 19 whole packages before it do
    not replace the good file of an earlier run, the error says so, no temporary file is left;
    standard output still gets every package before the fault, and --lenient writes them."""
    from rtde_spec.recipes.codec import RecipeCodec

    names = ["timestamp", "robot_mode", "actual_q"]
    codec = RecipeCodec.for_names(names, "output")
    packages = b"".join(
        codec.encode_package({"timestamp": i / 500, "robot_mode": 7, "actual_q": (0.1 * i,) * 6}, 1)
        for i in range(20)
    )
    whole, cut = tmp_path / "whole.bin", tmp_path / "cut.bin"
    whole.write_bytes(packages)
    cut.write_bytes(packages[:-9])
    out = tmp_path / f"out.{suffix}"
    recipe = ",".join(names)
    assert run(capsys, "decode", str(whole), "--recipe", recipe, "-o", str(out))[0] == 0
    before = state(tmp_path)
    code, err = run(capsys, "decode", str(cut), "--recipe", recipe, "-o", str(out))
    assert code == 1
    assert state(tmp_path) == before  # the file of the earlier run, byte for byte
    assert f"the 19 packages before it were not written to {out}" in err, err
    assert "the file that was there is as it was" in err and "--lenient" in err, err
    no_temp_files(tmp_path)
    fresh = tmp_path / f"fresh.{suffix}"
    code, err = run(capsys, "decode", str(cut), "--recipe", recipe, "-o", str(fresh))
    assert code == 1 and not fresh.exists() and "no partial file)" in err, err
    if suffix == "jsonl":  # standard output has streamed them: they are there before the error
        result = cli("decode", str(cut), "--recipe", recipe, "--jsonl")
        assert result.returncode == 1 and len(result.stdout.splitlines()) == 19, result.stderr
    assert run(capsys, "decode", str(cut), "--recipe", recipe, "-o", str(fresh), "--lenient")[0] == 0
    assert fresh.exists()


def test_a_primary_decode_that_stops_at_a_fault_keeps_the_file_there(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same for primary/secondary messages: a message cut short keeps the earlier file."""
    import yaml

    from tests.helpers import DATA

    golden = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
    stream = b"".join(bytes.fromhex(c["hex"]) for c in golden[:6])
    whole, cut = tmp_path / "whole.bin", tmp_path / "cut.bin"
    whole.write_bytes(stream)
    cut.write_bytes(stream[:-3])
    out = tmp_path / "out.jsonl"
    assert run(capsys, "decode", "--protocol", "primary", str(whole), "-o", str(out))[0] == 0
    before = state(tmp_path)
    code, err = run(capsys, "decode", "--protocol", "primary", str(cut), "-o", str(out))
    assert code == 1 and state(tmp_path) == before, err
    assert "the 5 messages before it were not written" in err and "as it was" in err, err
    no_temp_files(tmp_path)


def test_an_output_folder_that_is_a_link_to_nothing_is_said_so(tmp_path: Path) -> None:
    """capture/examples/demo -o LINK, a symbolic link to a folder that does not exist, failed as
    "writing failed: File exists" (making the folder met the link)."""
    link = tmp_path / "link"
    link.symlink_to(tmp_path / "nowhere")
    capture = tmp_path / "c.pcap"
    capture.write_bytes(b"")
    said = f"is a symbolic link to {tmp_path / 'nowhere'}, which does not exist"
    to = str(link)
    commands = (["capture", str(capture), "-o", to], ["examples", to], ["demo", "-o", to])
    for args in commands:
        done = cli(*args)
        assert done.returncode == 2 and said in done.stderr, done.stderr
    assert not (tmp_path / "nowhere").exists()


def test_parquet_to_a_pipe_is_refused_before_it_is_opened(fifo: Path, tmp_path: Path) -> None:
    """Parquet's writer seeks in its file: to a FIFO it failed with "lseek failed" once a reader
    came, and waited for ever for one that never did. Now a usage error names the streaming formats."""
    import sys

    data = tmp_path / "data.bin"
    data.write_bytes(bytes.fromhex("00045601"))
    argv = [sys.executable, "-m", "rtde_spec", "decode", str(data), "-o", str(fifo), "--format", "parquet"]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60)
    assert done.returncode == 2, done.stderr
    assert "cannot be written to a pipe" in done.stderr, done.stderr
    assert "--format csv or jsonl" in done.stderr, done.stderr


def test_a_capture_whose_tables_cannot_be_named_leaves_no_empty_folders(tmp_path: Path) -> None:
    """A 236-character capture name: its tables' names are too long, said clearly, but each
    table's robot= and date= folders (52 of them) were left behind empty."""
    from tests.capture_files import Conversation, write

    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    capture = write(tmp_path / ("r" * 236 + ".pcap"), [conv])
    out = tmp_path / "out"
    done = cli("capture", str(capture), "-o", str(out))
    assert done.returncode == 1 and "too long" in done.stderr, done.stderr
    assert [p for p in out.rglob("*")] == []


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="/dev/full is Linux's")
def test_every_command_that_prints_names_a_full_standard_output() -> None:
    """`fields > /dev/full` said "[Errno 28] No space left on device", naming nothing, and
    `--help > /dev/full` exited 0: the text was lost with no word."""
    import sys

    from rtde_spec.examples import __file__ as examples

    recipe = str(Path(examples).parent / "files" / "rtde_config.xml")
    for args in (["fields"], ["validate", recipe], ["--help"], ["decode", "--help"], ["--version"]):
        with open("/dev/full", "wb") as full:
            argv = [sys.executable, "-m", "rtde_spec", *args]
            done = subprocess.run(argv, stdout=full, stderr=subprocess.PIPE, text=True)
        assert done.returncode == 1, (args, done.stderr)
        assert done.stderr == "error: standard output: writing failed: the disk is full\n", (
            args,
            done.stderr,
        )


def test_standard_output_to_a_pipe_closed_early_is_no_error() -> None:
    """`rtde-spec fields | head -1`: the reader closing the pipe is not ours to report."""
    import sys

    reader = subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "fields"], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    assert reader.stdout is not None and reader.stderr is not None
    assert reader.stdout.readline().startswith(b"name")
    reader.stdout.close()
    assert reader.wait(timeout=60) == 0
    assert reader.stderr.read() == b""


def test_decode_to_a_full_standard_output_names_it(tmp_path: Path) -> None:
    """`decode ... > /dev/full` said "[Errno 28] No space left on device", naming nothing."""
    import sys

    import yaml

    from tests.helpers import DATA

    golden = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
    primary = tmp_path / "primary.bin"
    primary.write_bytes(b"".join(bytes.fromhex(c["hex"]) for c in golden[:5]))
    for args in (["00045601", "--jsonl"], ["00045601"], ["--protocol", "primary", str(primary), "--jsonl"]):
        with open("/dev/full", "wb") as full:
            argv = [sys.executable, "-m", "rtde_spec", "decode", *args]
            done = subprocess.run(argv, stdout=full, stderr=subprocess.PIPE, text=True)
        assert done.returncode == 1, done.stderr
        assert done.stderr == "error: standard output: writing failed: the disk is full\n", done.stderr
