"""One capture on several cores (issue 30.4): `capture FILE --jobs N` prepares batches on worker
threads while the file is read on, and writes the same tables, byte for byte, as `--jobs 1`."""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from rtde_spec import Catalogue, RecipeCodec, build
from rtde_spec.capture.decoder import decode_to_directory
from rtde_spec.capture.tables.ordered_writes import SWITCH_INTERVAL, OrderedWrites
from rtde_spec.capture.tables.sink import DirectorySink
from rtde_spec.errors import OutputError
from tests.capture_files import Conversation, write
from tests.test_cli import cli

BIG = (  # a 58-field-like recipe: ~500-byte packages, so a few thousand span several 8 MB blocks
    "timestamp", "target_q", "target_qd", "target_qdd", "target_current", "target_moment", "actual_q",
    "actual_qd", "actual_current", "joint_control_output", "actual_TCP_pose", "actual_TCP_speed",
    "actual_TCP_force", "target_TCP_pose", "target_TCP_speed", "actual_digital_input_bits",
    "joint_temperatures", "actual_execution_time", "robot_mode", "joint_mode", "safety_mode",
    "actual_tool_accelerometer", "speed_scaling", "target_speed_fraction", "actual_momentum",
    "actual_main_voltage", "actual_robot_voltage", "actual_robot_current", "actual_joint_voltage",
    "actual_digital_output_bits", "runtime_state", "output_int_register_0",
)  # fmt: skip
SMALL = ("timestamp", "actual_q", "robot_mode")


def _session(conv: Conversation, names: tuple[str, ...], recipe_id: int) -> RecipeCodec:
    cat = Catalogue.builtin()
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=list(names)))
    types = [cat.get(n, "output").type for n in names]  # type: ignore[union-attr]
    conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=recipe_id, variable_types=types))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))
    return RecipeCodec.for_names(list(names), "output", cat)


def _package(codec: RecipeCodec, i: int, recipe_id: int) -> bytes:
    values: dict[str, object] = {}
    for item in codec.items:
        one: object = (i * 0.25 + item.wire.size) if item.wire.kind == "float" else (i * 7) % 100
        values[item.name] = tuple([one] * item.wire.count) if item.wire.count > 1 else one
    values["timestamp"] = i * 0.002
    return codec.encode_package(values, recipe_id=recipe_id)


@pytest.fixture(scope="module")
def mixed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two RTDE connections (a big and a small recipe) interleaved, each with long runs of one
    package per segment (the bulk path), packages cut across segments and several per segment
    (the per-package path into the same table), and a text message between the runs."""
    big = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    small = Conversation(("10.0.0.3", 52000), ("10.0.0.11", 30004), time=1_700_000_000.001)
    big_codec, small_codec = _session(big, BIG, 1), _session(small, SMALL, 2)
    n = 0
    for part in range(6):
        for _ in range(3000):
            big.send("server", _package(big_codec, n, 1))
            small.send("server", _package(small_codec, n, 2))
            n += 1
        stream = b"".join(_package(big_codec, n + k, 1) for k in range(40))
        for at in range(0, len(stream), 700):  # cut across segments: framed package by package
            big.send("server", stream[at : at + 700])
        n += 40
        text = build("text_message", message=f"part {part}", source="test", warning_level=1)
        big.send("server", text)
    path = write(tmp_path_factory.mktemp("jobs") / "mixed.pcap", [big, small])
    assert path.stat().st_size > 2 * (8 << 20), "several blocks of the file"
    return path


def digests(folder: Path) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def test_one_file_with_jobs_writes_the_same_tables_byte_for_byte(tmp_path: Path, mixed: Path) -> None:
    one, two = tmp_path / "one", tmp_path / "two"
    first = cli("capture", str(mixed), "-o", str(one))
    second = cli("capture", str(mixed), "-o", str(two), "--jobs", "2")
    assert first.returncode == second.returncode == 0, second.stderr
    assert first.stdout == second.stdout and first.stderr == second.stderr
    files = digests(one)
    assert len([f for f in files if f.endswith(".parquet")]) >= 4  # setup, text and two data tables
    assert files == digests(two)
    table = pq.read_table(next(one.glob("rtde_outputs_1/*/*/*.parquet")))
    stamps = table.column("timestamp").to_pylist()
    assert len(stamps) == 6 * 3040 and stamps == sorted(stamps), "every row, in capture order"


@pytest.mark.parametrize("workers", [1, 3])
def test_workers_give_the_same_rows_through_the_api(tmp_path: Path, mixed: Path, workers: int) -> None:
    base = decode_to_directory(mixed, tmp_path / "a")
    ours = decode_to_directory(mixed, tmp_path / "b", workers=workers)
    assert ours.tables == base.tables and ours.line() == base.line()
    assert digests(tmp_path / "a") == digests(tmp_path / "b")


def test_csv_with_workers_is_written_as_without(tmp_path: Path, mixed: Path) -> None:
    """Formats without a prepared path take the batches in the decoding thread: the same files."""
    base = decode_to_directory(mixed, tmp_path / "a", "csv")
    ours = decode_to_directory(mixed, tmp_path / "b", "csv", workers=2)
    assert ours.tables == base.tables
    assert digests(tmp_path / "a") == digests(tmp_path / "b")


def test_ordered_writes_keep_the_order_they_were_given() -> None:
    import time

    got: list[object] = []
    before = sys.getswitchinterval()
    writes = OrderedWrites(workers=3, write=lambda _k, _p, item: got.append(item), depth=4)

    def slow(value: int) -> int:
        time.sleep(0.002 * (value % 5))  # later items are often ready first
        return value

    for i in range(40):
        if i % 7 == 0:
            writes.add(("t", "r", "d"), None, f"row {i}")
        else:
            writes.add(("t", "r", "d"), slow, i)
        assert len(writes.queue) < 4
    assert sys.getswitchinterval() <= SWITCH_INTERVAL, "a worker waits at most this for the GIL"
    writes.finish()
    assert got == [f"row {i}" if i % 7 == 0 else i for i in range(40)]
    assert not any(t.is_alive() for t in writes.threads)
    assert sys.getswitchinterval() == before, "Python's own again"


def test_a_batch_that_cannot_be_prepared_stops_the_workers_and_is_raised_here() -> None:
    got: list[object] = []
    writes = OrderedWrites(workers=2, write=lambda _k, _p, item: got.append(item), depth=3)

    def prepare(value: int) -> int:
        if value == 5:
            raise ValueError("batch 5 is bad")
        return value

    with pytest.raises(ValueError, match="batch 5 is bad"):
        for i in range(50):
            writes.add(("t", "r", "d"), prepare, i)
        writes.finish()
    writes.drop()
    assert not any(t.is_alive() for t in writes.threads)
    assert got == list(range(len(got))) and len(got) <= 5, "in order, and nothing after the bad batch"


def test_a_failed_batch_keeps_no_table_and_names_the_error(tmp_path: Path, mixed: Path) -> None:
    """An error in a worker reaches the decoding thread; no table of the capture is left behind."""
    out = tmp_path / "out"
    old = DirectorySink._write

    def failing(self: DirectorySink, key: tuple[str, str, str], prepared: bool, item: object) -> None:
        if prepared and key[0] == "rtde_outputs_2" and self.rows.get(key[0], 0) > 5000:
            raise OutputError("no space left on the device", subject="test")
        old(self, key, prepared, item)

    DirectorySink._write = failing  # type: ignore[method-assign]
    try:
        with pytest.raises(OutputError, match=r"no table of .* was kept"):
            decode_to_directory(mixed, out, workers=2)
    finally:
        DirectorySink._write = old  # type: ignore[method-assign]
    assert not [p for p in out.rglob("*") if p.is_file()], "nothing half-written is left"


def _small_capture(path: Path) -> Path:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    codec = _session(conv, SMALL, 1)
    for i in range(50):
        conv.send("server", _package(codec, i, 1))
    return write(path, [conv])


def test_placing_a_capture_leaves_the_empty_folders_of_others_alone(tmp_path: Path) -> None:
    """`capture --jobs N` decodes files in workers while the parent places finished ones. A
    worker makes a table's partition folder at its first row and its file at its first row
    group: placing another file pruned every empty partition folder of the output, that one
    too, and the worker failed ("its folder does not exist"; a race seen 1 run in ~50)."""
    out = tmp_path / "out"
    fresh = out / "rtde_outputs_7" / "robot=10.0.0.10" / "date=2023-11-14"
    fresh.mkdir(parents=True)  # another capture's, its file not begun yet
    decode_to_directory(_small_capture(tmp_path / "a.pcap"), out)
    assert fresh.is_dir()
    assert any((out / "rtde_outputs_1").rglob("a*.parquet"))


def test_a_table_whose_folder_was_removed_before_its_file_is_made_is_still_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same race from the worker's side: its folder made, then removed before the file is
    created (pinned Parquet files are created at their first row group): it is made again."""
    import rtde_spec.capture.tables.sink as sink

    real, removed = sink.open_writer, []

    def folder_removed_meanwhile(fmt: str, path: Path | str, **options: object) -> object:
        writer = real(fmt, path, **options)  # type: ignore[arg-type]
        if not removed:  # the file is not made yet (pinned Parquet: at its first row group)
            Path(path).parent.rmdir()
            removed.append(path)
        return writer

    monkeypatch.setattr(sink, "open_writer", folder_removed_meanwhile)
    out = tmp_path / "out"
    summary = decode_to_directory(_small_capture(tmp_path / "a.pcap"), out)
    assert removed and summary.tables.get("rtde_outputs_1") == 50
    assert sum(pq.read_metadata(f).num_rows for f in (out / "rtde_outputs_1").rglob("*.parquet")) == 50


def test_a_killed_runs_temporary_files_are_removed_when_the_capture_is_placed_again(tmp_path: Path) -> None:
    """`kill -9` of a capture while it wrote its listing or a table left `.NAME.part-PID` files no
    process could remove (its own clean-up never ran). Placing the same capture again removes
    those of processes that are gone, and leaves a live process's alone."""
    import subprocess

    capture = _small_capture(tmp_path / "a.pcap")
    out = tmp_path / "out"
    decode_to_directory(capture, out)
    placed = sorted(p for p in out.rglob("*") if p.is_file())
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()  # its process id is one of a process that is gone
    stale = [p.with_name(f".{p.name}.part-{dead.pid}") for p in placed]
    live = [p.with_name(f".{p.name}.part-1") for p in placed]  # init's: a live writer
    for path in (*stale, *live):
        path.write_bytes(b"")
    decode_to_directory(capture, out)
    assert not any(p.exists() for p in stale)
    assert all(p.exists() for p in live)
    assert sorted(p for p in out.rglob("*") if p.is_file() and ".part-" not in p.name) == placed
