"""Streaming output: every format readable and equal to the decoder's values; the protocol state."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from rtde_spec import ProtocolState, RecipeCodec, StreamDecoder, build
from rtde_spec.rtde.codec import decode_stream

from .test_cli import cli

NAMES = ["timestamp", "actual_q", "robot_mode", "output_bit_register_64"]
CODEC = RecipeCodec.for_names(NAMES, "output")


def packages(count: int, start: int = 0) -> bytes:
    return b"".join(
        CODEC.encode_package(
            {"timestamp": i * 0.002, "actual_q": tuple(i + j / 10 for j in range(6)), "robot_mode": i % 8,
             "output_bit_register_64": i % 2 == 0},
            recipe_id=1,
        )
        for i in range(start, start + count)
    )  # fmt: skip


@pytest.fixture
def stream(tmp_path: Path) -> Path:
    # setup exchange as the controller sends it, data, a text message in the middle, more data
    data = build("request_protocol_version_reply", accepted=True)
    data += packages(3000) + build("text_message", message="hello", source="ctl", warning_level=3)
    data += packages(2000, start=3000)
    path = tmp_path / "controller.bin"
    path.write_bytes(data)
    return path


def test_parquet_and_csv_hold_every_data_package_with_ur_column_names(stream: Path, tmp_path: Path) -> None:
    recipe = ",".join(NAMES)
    parquet, table_csv = tmp_path / "out.parquet", tmp_path / "out.csv"
    result = cli("decode", str(stream), "--recipe", recipe, "-o", str(parquet))
    assert result.returncode == 0, result.stderr
    assert "request_protocol_version_reply x1" in result.stderr and "text_message x1" in result.stderr
    table = pq.read_table(parquet)
    expected = ["timestamp", *(f"actual_q_{i}" for i in range(6)), "robot_mode", "output_bit_register_64"]
    assert table.column_names == expected and table.num_rows == 5000
    assert table.column("actual_q_3")[4321].as_py() == pytest.approx(4321.3)
    assert table.column("robot_mode")[4321].as_py() == 4321 % 8
    assert cli("decode", str(stream), "--recipe", recipe, "-o", str(table_csv)).returncode == 0
    with open(table_csv, newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == expected and len(rows) == 5001
    assert float(rows[4000][0]) == pytest.approx(3999 * 0.002) and float(rows[4000][1]) == 3999.0


def test_json_lines_and_json_keep_every_package_in_order(stream: Path, tmp_path: Path) -> None:
    jsonl, whole = tmp_path / "out.jsonl", tmp_path / "out.json"
    assert cli("decode", str(stream), "--recipe", ",".join(NAMES), "-o", str(jsonl)).returncode == 0
    lines = [json.loads(line) for line in jsonl.read_text().splitlines()]
    assert len(lines) == 5002
    assert lines[0]["package"] == "request_protocol_version_reply"
    assert lines[3001]["package"] == "text_message" and lines[3001]["message"] == "hello"
    assert lines[3002]["actual_q"] == pytest.approx([3000 + j / 10 for j in range(6)])
    offsets = [line["offset"] for line in lines]
    assert offsets == sorted(offsets) and len(set(offsets)) == len(offsets)
    assert cli("decode", str(stream), "--recipe", ",".join(NAMES), "-o", str(whole)).returncode == 0
    assert json.loads(whole.read_text()) == lines


def test_streaming_equals_decoding_the_whole_buffer_at_any_chunk_size(stream: Path) -> None:
    data = stream.read_bytes()
    whole = [m.NAME for _, m in decode_stream(data)]
    for chunk in (1, 7, 1180, 65536):
        decoder = StreamDecoder("controller", codec=CODEC)
        names: list[str] = []
        rows = 0
        for start in range(0, len(data), chunk):
            for item in decoder.feed(data[start : start + chunk]):
                if hasattr(item, "array"):
                    rows += len(item.array)
                    names += ["data_package"] * len(item.array)
                else:
                    names.append(item.message.NAME)
        decoder.close()
        assert names == whole and rows == 5000, chunk


def test_protocol_state_follows_the_accepted_request() -> None:
    both = ProtocolState()
    assert both.version == 1  # the controller speaks protocol 1 until a request is accepted
    both.on_request(2)
    assert both.version == 1
    both.on_reply(False)
    assert both.version == 1
    both.on_request(2)
    both.on_reply(True)
    assert both.version == 2
    controller_side = ProtocolState(one_sided=True)
    controller_side.on_reply(True)  # the request is not in view: the newest version
    assert controller_side.version == 2
    client_side = ProtocolState(one_sided=True)
    client_side.on_request(2)  # the reply is not in view: taken as accepted
    assert client_side.version == 2


def test_parquet_without_a_file_is_a_usage_error(stream: Path) -> None:
    result = cli("decode", str(stream), "--recipe", ",".join(NAMES), "--format", "parquet")
    assert result.returncode == 2 and "-o FILE.parquet" in result.stderr


def test_session_learns_a_recipe_sent_with_a_trailing_comma() -> None:
    from rtde_spec import SessionDecoder

    session = SessionDecoder()
    session.feed("client", build("setup_outputs_v1", variable_names=["timestamp", "robot_mode", ""]))
    session.feed("controller", build("setup_outputs_v1_reply", variable_types=["DOUBLE", "INT32"]))
    package = RecipeCodec.for_names(["timestamp", "robot_mode"], "output").encode_package(
        {"timestamp": 2.5, "robot_mode": 7}, recipe_id=1
    )
    assert session.feed("controller", package).values == {"timestamp": 2.5, "robot_mode": 7}


def test_data_package_columns_are_required_in_parquet(stream: Path, tmp_path: Path) -> None:
    """No data package lacks a value, so its columns are REQUIRED: no definition levels to encode."""
    parquet = tmp_path / "out.parquet"
    assert cli("decode", str(stream), "--recipe", ",".join(NAMES), "-o", str(parquet)).returncode == 0
    schema = pq.ParquetFile(parquet).schema
    assert [schema.column(i).max_definition_level for i in range(len(schema))] == [0] * len(schema)
    assert not any(field.nullable for field in pq.read_schema(parquet))


def test_a_later_batch_missing_a_value_is_an_error_naming_the_column(tmp_path: Path) -> None:
    import numpy as np

    from rtde_spec.errors import UsageError
    from rtde_spec.output.parquet import ParquetWriter

    writer = ParquetWriter(str(tmp_path / "out.parquet"))
    writer.write_columns({"timestamp": np.arange(3.0), "actual_q": np.ones((3, 6))})
    writer.write({"timestamp": 1.5, "actual_q": [2.0] * 6})  # a row that fits: cast to the file's types
    writer.write({"timestamp": None, "actual_q": [2.0] * 6})
    with pytest.raises(UsageError, match=r"Parquet output.*'timestamp'.*null"):
        writer.close()
    writer = ParquetWriter(str(tmp_path / "other.parquet"))
    writer.write_columns({"timestamp": np.arange(3.0)})
    writer.write({"robot_mode": 7})
    with pytest.raises(UsageError, match=r"lacks the file's columns \['timestamp'\]"):
        writer.close()


# --- nothing lost: files appear only with rows in them (issue 18.1) ----------------------------

FILE_FORMATS = ["csv", "jsonl", "json", "parquet", "table"]


def leftover_temps(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".part-" in p.name)


@pytest.mark.parametrize("fmt", FILE_FORMATS)
def test_a_writer_replaces_an_existing_file_only_when_it_closes_with_rows(tmp_path: Path, fmt: str) -> None:
    from rtde_spec import open_writer

    out = tmp_path / f"out.{fmt}"
    old = b"someone's earlier results\n"
    out.write_bytes(old)
    array = CODEC.decode_many(packages(50))
    columns = {name: array[name] for name in CODEC.names}
    open_writer(fmt, out).close()  # no rows: the run produced nothing
    assert out.read_bytes() == old and leftover_temps(tmp_path) == []
    writer = open_writer(fmt, out)
    writer.write_columns(columns)
    writer.flush()
    assert out.read_bytes() == old, "the file changed before the writer closed"
    writer.abort()  # the caller's run failed: nothing of it appears
    assert out.read_bytes() == old and leftover_temps(tmp_path) == []
    writer = open_writer(fmt, out)
    writer.write_columns(columns)
    writer.close()
    assert out.read_bytes() != old and leftover_temps(tmp_path) == []
    if fmt == "parquet":
        assert pq.read_table(out).num_rows == 50
    elif fmt in ("csv", "jsonl"):
        assert len(out.read_text().splitlines()) == 50 + (fmt == "csv")
    null = open_writer(fmt, "/dev/null")  # a device is written, never replaced by a file
    null.write_columns(columns)
    null.close()
    assert Path("/dev/null").is_char_device()


@pytest.mark.parametrize("fmt", [*FILE_FORMATS, "mcap"])
def test_a_closed_writer_refuses_rows_and_closes_again_quietly(tmp_path: Path, fmt: str) -> None:
    """Rows written after close() were dropped without a word (Parquet left a temporary file
    behind), and CSV's second close raised ValueError: underlying buffer has been detached."""
    from rtde_spec import UsageError, open_writer

    out = tmp_path / f"out.{fmt}"
    writer = open_writer(fmt, out)
    writer.write({"timestamp": 1.0, "robot_mode": 7})
    writer.close()
    kept = out.read_bytes()
    writer.close()
    with pytest.raises(UsageError, match="this writer is closed"):
        writer.write({"timestamp": 2.0, "robot_mode": 7})
    with pytest.raises(UsageError, match="this writer is closed"):
        writer.write_columns({})
    writer.abort()
    assert out.read_bytes() == kept and leftover_temps(tmp_path) == []


@pytest.mark.parametrize("fmt", [*FILE_FORMATS, "mcap"])
def test_a_writer_in_a_with_block_is_closed_or_aborted_on_an_error(tmp_path: Path, fmt: str) -> None:
    """A writer neither closed nor aborted (an error between its rows) left `.NAME.part-PID`."""
    from rtde_spec import open_writer

    out = tmp_path / f"out.{fmt}"
    with open_writer(fmt, out) as writer:
        writer.write({"timestamp": 1.0, "robot_mode": 7})
    kept = out.read_bytes()
    assert kept and leftover_temps(tmp_path) == []
    with pytest.raises(RuntimeError, match="the caller's own"), open_writer(fmt, out) as writer:
        writer.write({"timestamp": 2.0, "robot_mode": 7})
        raise RuntimeError("the caller's own error")
    assert out.read_bytes() == kept and leftover_temps(tmp_path) == []


def test_a_failed_decode_leaves_an_existing_output_byte_identical(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.bin"
    garbage.write_bytes(b"\x00\x03\x55" * 100)  # a package of size 3 and an unknown type: no rows
    for fmt in ("csv", "jsonl", "json"):
        out = tmp_path / f"kept.{fmt}"
        out.write_bytes(b"yesterday's decode\n")
        result = cli("decode", str(garbage), "--recipe", ",".join(NAMES), "-o", str(out), "--format", fmt)
        assert result.returncode != 0 and "error" in result.stderr
        assert out.read_bytes() == b"yesterday's decode\n", fmt
    assert leftover_temps(tmp_path) == []


def test_split_parts_read_as_one_dataset_and_replace_an_earlier_runs_parts(tmp_path: Path) -> None:
    import pyarrow.dataset as ds

    from rtde_spec import open_writer
    from rtde_spec.output.split import parse_split

    assert parse_split("10min").seconds == 600 and parse_split("100MB").size == 100_000_000
    assert parse_split("2GiB").size == 2 << 30 and parse_split("1.5h").seconds == 5400
    for bad in ("60", "10 parsecs", "0s", "1kB", "-5s"):
        with pytest.raises(Exception, match="--split"):
            parse_split(bad)
    stale = tmp_path / "run_0007.parquet"
    stale.write_bytes(b"an earlier, longer run's part")
    unrelated = tmp_path / "run_old.parquet"
    unrelated.write_bytes(b"not a part")
    writer = open_writer("parquet", tmp_path / "run.parquet", split=parse_split("64kB"))
    for start in range(0, 5000, 500):
        array = CODEC.decode_many(packages(500, start))
        writer.write_columns({name: array[name] for name in CODEC.names})
        writer.flush()
    writer.close()
    names = sorted(p.name for p in tmp_path.glob("run_*.parquet"))
    found = [n for n in names if n != "run_old.parquet"]
    assert len(found) >= 3 and found == [f"run_{i:04d}.parquet" for i in range(len(found))]
    assert unrelated.exists() and not stale.exists() and leftover_temps(tmp_path) == []
    table = ds.dataset([str(tmp_path / n) for n in found], format="parquet").to_table()
    assert table.column("timestamp").to_pylist() == [i * 0.002 for i in range(5000)]


def test_a_small_file_written_whole_replaces_the_old_one_or_leaves_it(tmp_path: Path) -> None:
    from rtde_spec.output.partfile import write_whole

    listing = tmp_path / "recipes-x.json"
    listing.write_bytes(b"[old]\n")
    with pytest.raises(TypeError):
        write_whole(listing, "text, not bytes")  # type: ignore[arg-type]  # fails while writing
    assert listing.read_bytes() == b"[old]\n" and leftover_temps(tmp_path) == []
    write_whole(listing, b"[new]\n", durable=True)
    assert listing.read_bytes() == b"[new]\n" and leftover_temps(tmp_path) == []


def test_an_output_whose_name_leaves_no_room_for_the_temporary_mark_is_written(tmp_path: Path) -> None:
    """A legal 244-byte name (Linux takes 255) was refused as "too long": its temporary name
    beside it, `.NAME.part-PID`, went past 255 bytes. A stale one of a killed run is found."""
    import os
    import subprocess

    from rtde_spec.output.partfile import write_with
    from rtde_spec.output.tempnames import leftovers, temp_path

    target = tmp_path / ("é" * 100 + "x" * 40 + ".csv")
    assert len(os.fsencode(target.name)) == 244
    write_with(target, lambda out: out.write(b"timestamp\n0.5\n"))
    assert target.read_bytes() == b"timestamp\n0.5\n"
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
    done = cli("decode", "00045601", "--from", "controller", "--format", "csv", "-o", str(target))
    assert done.returncode == 0, done.stderr
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
    assert b"protocol_version" in target.read_bytes()
    dead = subprocess.Popen(["true"])  # a process that has ended: the run that left a file
    dead.wait()
    stale = temp_path(target).with_name(temp_path(target).name.rpartition("-")[0] + f"-{dead.pid}")
    stale.write_bytes(b"cut off")
    assert leftovers(target) == [stale]


def test_a_killed_split_run_of_a_long_name_leaves_its_parts_found(tmp_path: Path) -> None:
    """The parts' shortened temporary names were not matched: `record --split` killed with a
    240-byte output name neither reported nor removed them."""
    import subprocess

    from rtde_spec.output.split import part_path
    from rtde_spec.output.tempnames import leftovers, temp_path

    target = tmp_path / ("p" * 236 + ".csv")
    dead = subprocess.Popen(["true"])
    dead.wait()
    stale = []
    for path in (target, part_path(target, 0), part_path(target, 7)):
        temp = temp_path(path)
        stale.append(temp.with_name(temp.name.rpartition("-")[0] + f"-{dead.pid}"))
        stale[-1].write_bytes(b"cut off")
    assert leftovers(target) == sorted(stale)


def test_a_second_file_of_a_target_not_yet_in_place_gets_its_own_temporary_name(tmp_path: Path) -> None:
    """`capture --jobs 2` given one capture twice: a worker's second decode truncated the tables
    it had prepared for the parent to place (the same `.NAME.part-PID`), and the parent's second
    rename failed as "its folder does not exist". Each file not yet in place has its own name,
    and one a killed run left under the new name is found as a leftover."""
    import os
    import subprocess

    from rtde_spec.output.partfile import Part
    from rtde_spec.output.tempnames import leftovers, temp_path

    target = tmp_path / "t.parquet"
    first = Part(target)
    first.temp.write_bytes(b"prepared, not yet placed")
    second = Part(target)
    assert second.temp != first.temp and second.temp.name == f"{first.temp.name}-2"
    second.temp.write_bytes(b"the second")
    first.commit()
    assert target.read_bytes() == b"prepared, not yet placed"
    second.commit()
    assert target.read_bytes() == b"the second" and [p.name for p in tmp_path.iterdir()] == ["t.parquet"]
    dead = subprocess.Popen(["true"])
    dead.wait()
    stale = tmp_path / temp_path(target).name.replace(f"-{os.getpid()}", f"-{dead.pid}-2")
    stale.write_bytes(b"cut off")
    assert leftovers(target) == [stale]


def test_a_capture_given_twice_is_decoded_once(tmp_path: Path) -> None:
    """A folder and a glob that both hold a capture: it was decoded twice into the same tables,
    its rows counted twice in the report; with --jobs 2 the second could fail the command. A
    glob that matches a folder searches it, as the folder given (it was an "Is a directory")."""
    from rtde_spec import build
    from tests.capture_files import Conversation, write

    folder = tmp_path / "captures"
    folder.mkdir()
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    write(folder / "one.pcap", [conv])
    for jobs in ("1", "2"):
        out = tmp_path / f"out{jobs}"
        done = cli("capture", str(folder), str(folder / "*.pcap"), str(tmp_path / "capt*"), "-o", str(out),
                   "--jobs", jobs, "--lenient")  # fmt: skip
        assert done.returncode == 0, done.stderr
        assert f"note: given more than once, decoded once: {folder / 'one.pcap'}" in done.stderr
        assert done.stdout.count("one.pcap: ") == 1, done.stdout


def test_parquet_output_takes_a_file_name_that_is_not_utf8(tmp_path: Path) -> None:
    """Linux names are bytes: a name that is not UTF-8 (Python keeps it as surrogates) failed
    for Parquet alone, with "'utf-8' codec can't encode characters ... surrogates not allowed"."""
    import os
    import subprocess
    import sys

    import pyarrow as pa

    from rtde_spec.recipes.codec import RecipeCodec

    names = ["timestamp", "actual_q"]
    codec = RecipeCodec.for_names(names, "output")
    data = tmp_path / "data.bin"
    packages = [codec.encode_package({"timestamp": i / 500, "actual_q": (0.0,) * 6}, 1) for i in range(7)]
    data.write_bytes(b"".join(packages))
    target = os.fsdecode(os.fsencode(str(tmp_path)) + b"/d\xff\xfe.parquet")
    argv = [sys.executable, "-m", "rtde_spec", "decode", str(data), "--recipe", ",".join(names), "-o", target]
    done = subprocess.run([os.fsencode(a) for a in argv], capture_output=True)
    assert done.returncode == 0, done.stderr
    table = pq.read_table(pa.BufferReader(Path(target).read_bytes()))
    assert table.num_rows == 7 and table.column_names == ["timestamp", *(f"actual_q_{i}" for i in range(6))]
