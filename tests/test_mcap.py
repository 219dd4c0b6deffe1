"""MCAP output: the same input decoded to Parquet and to MCAP holds the same values, read back
with mcap's own reader; schemas come from the spec; log times from the controller or capture."""

from __future__ import annotations

import argparse
import json
import math
import time
from fractions import Fraction
from pathlib import Path
from typing import Any

import jsonschema
import pyarrow.parquet as pq
import pytest
from mcap.reader import make_reader

from rtde_spec import RecipeCodec, build
from rtde_spec.cli.decode_cmd import decode_into
from rtde_spec.cli.primary_output import run_primary
from rtde_spec.output.mcap import McapWriter
from rtde_spec.output.writers import open_writer

from .test_cli import cli

NAMES = ["timestamp", "actual_q", "robot_mode", "output_bit_register_64", "actual_digital_input_bits"]
CODEC = RecipeCodec.for_names(NAMES, "output")
ROWS = 3000


def _values(i: int) -> dict[str, Any]:
    q = tuple(i + j / 10 for j in range(6))
    return {
        "timestamp": 1000.0 + i * 0.002,
        "actual_q": (math.nan, *q[1:]) if i == 7 else q,  # a NaN: null in JSON, NaN in Parquet
        "robot_mode": i % 8,
        "output_bit_register_64": i % 2 == 0,
        "actual_digital_input_bits": 2**63 + i,  # UINT64 beyond int64
    }


@pytest.fixture
def stream(tmp_path: Path) -> Path:
    data = build("request_protocol_version_reply", accepted=True)
    data += b"".join(CODEC.encode_package(_values(i), recipe_id=1) for i in range(ROWS // 2))
    data += build("text_message", message="hello", source="ctl", warning_level=3)
    data += b"".join(CODEC.encode_package(_values(i), recipe_id=1) for i in range(ROWS // 2, ROWS))
    path = tmp_path / "controller.bin"
    path.write_bytes(data)
    return path


def decode_to_mcap(stream: Path, target: Path) -> int:
    """What `rtde-spec decode STREAM --recipe ... -o TARGET.mcap` runs once --format mcap is wired."""
    writer = open_writer("mcap", target, background=True)
    args = argparse.Namespace(
        data=str(stream), sender="controller", protocol_version=None, lenient=False, no_progress=True
    )
    try:
        return decode_into(writer, args, CODEC, "mcap")
    finally:
        writer.close()


def read_mcap(path: Path) -> tuple[dict[str, list[tuple[int, dict[str, Any]]]], dict[str, dict[str, Any]]]:
    """Messages by topic (log time, decoded JSON) and each topic's schema, via mcap's reader."""
    messages: dict[str, list[tuple[int, dict[str, Any]]]] = {}
    schemas: dict[str, dict[str, Any]] = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema is not None and schema.encoding == "jsonschema"
            assert channel.message_encoding == "json"
            schemas[channel.topic] = json.loads(schema.data)
            messages.setdefault(channel.topic, []).append((message.log_time, json.loads(message.data)))
    return messages, schemas


def _same(parquet_value: Any, mcap_value: Any) -> bool:
    if isinstance(parquet_value, float) and math.isnan(parquet_value):
        return mcap_value is None
    return bool(parquet_value == mcap_value) and type(parquet_value) is type(mcap_value)


def test_every_value_of_a_decode_reads_back_as_in_parquet(stream: Path, tmp_path: Path) -> None:
    parquet, mcap = tmp_path / "out.parquet", tmp_path / "out.mcap"
    assert cli("decode", str(stream), "--recipe", ",".join(NAMES), "-o", str(parquet)).returncode == 0
    assert decode_to_mcap(stream, mcap) == ROWS + 2
    table = pq.read_table(parquet).to_pylist()
    messages, schemas = read_mcap(mcap)
    assert sorted(messages) == [
        "/rtde/outputs/1",
        "/rtde/request_protocol_version_reply",
        "/rtde/text_message",
    ]
    data = messages["/rtde/outputs/1"]
    assert len(data) == len(table) == ROWS
    for row, (_, message) in zip(table, data, strict=True):
        assert message["recipe_id"] == 1
        for name in NAMES:
            if name == "actual_q":
                for j in range(6):
                    assert _same(row[f"actual_q_{j}"], message["actual_q"][j]), (row, message)
            else:
                assert _same(row[name], message[name]), (name, row[name], message[name])
    text = messages["/rtde/text_message"][0][1]
    assert (text["message"], text["source"], text["warning_level"]) == ("hello", "ctl", 3)
    assert messages["/rtde/request_protocol_version_reply"][0][1]["accepted"] is True
    for topic, topic_messages in messages.items():  # each message is what its schema says
        validator = jsonschema.Draft202012Validator(schemas[topic])
        for _, message in topic_messages:
            if message.get("actual_q", [0])[0] is not None:  # (NaN is null, which "number" is not)
                validator.validate(message)


def test_schemas_come_from_the_spec(stream: Path, tmp_path: Path) -> None:
    decode_to_mcap(stream, tmp_path / "out.mcap")
    _, schemas = read_mcap(tmp_path / "out.mcap")
    props = schemas["/rtde/outputs/1"]["properties"]
    assert (
        props["actual_q"]["type"] == "array"
        and props["actual_q"]["minItems"] == 6 == props["actual_q"]["maxItems"]
    )
    assert props["actual_q"]["items"] == {"type": "number"} and "[rad]" in props["actual_q"]["description"]
    assert props["robot_mode"]["type"] == "integer" and props["robot_mode"]["maximum"] == 2**31 - 1
    assert props["actual_digital_input_bits"]["maximum"] == 2**64 - 1
    assert props["output_bit_register_64"]["type"] == "boolean"
    assert props["timestamp"]["type"] == "number" and "[s]" in props["timestamp"]["description"]
    assert schemas["/rtde/text_message"]["properties"]["warning_level"]["type"] == "integer"


def test_log_times_follow_the_controller_timestamp_from_the_time_of_writing(
    stream: Path, tmp_path: Path
) -> None:
    before = time.time_ns()
    decode_to_mcap(stream, tmp_path / "out.mcap")
    messages, _ = read_mcap(tmp_path / "out.mcap")
    data = messages["/rtde/outputs/1"]
    first_time, first = data[0]
    assert before <= first_time <= time.time_ns()  # plausible: when it was written
    for log_time, message in data:  # the controller's spacing, to the nanosecond
        assert log_time - first_time == round(message["timestamp"] * 1e9) - round(first["timestamp"] * 1e9)
    text_time = messages["/rtde/text_message"][0][0]  # no timestamp: the time logged before it
    assert text_time == data[ROWS // 2 - 1][0]


def test_capture_rows_are_logged_at_their_capture_time(tmp_path: Path) -> None:
    import numpy as np

    writer = McapWriter(open(tmp_path / "cap.mcap", "wb"), topic="/rtde/outputs/1")
    writer.owns_stream = True
    times = 1.7e9 + np.arange(5) * 0.002
    array = CODEC.decode_many(b"".join(CODEC.encode_package(_values(i), 1) for i in range(5)))
    writer.write_columns(
        {"connection": np.full(5, "a:1->b:2"), "capture_time": times, **{n: array[n] for n in NAMES}}
    )
    writer.write({"connection": "a:1->b:2", "capture_time": 1.8e9, "level": 1, "message": "hi"})
    writer.close()
    messages, _ = read_mcap(tmp_path / "cap.mcap")
    got = messages["/rtde/outputs/1"]
    assert [t for t, _ in got] == [round(Fraction(t) * 10**9) for t in [*times.tolist(), 1.8e9]]  # to the ns
    assert got[0][1]["connection"] == "a:1->b:2" and got[3][1]["robot_mode"] == 3


def test_primary_messages_and_each_robot_state_sub_package_on_its_own_topic(tmp_path: Path) -> None:
    from importlib import resources

    text = resources.files("rtde_spec.examples").joinpath("primary_stream.hex").read_text()
    data = bytes.fromhex("".join(line for line in text.splitlines() if not line.startswith("#")))
    run_primary([data], "mcap", str(tmp_path / "p.mcap"))
    run_primary([data], "jsonl", str(tmp_path / "p.jsonl"))
    messages, schemas = read_mcap(tmp_path / "p.mcap")
    rows = [json.loads(line) for line in (tmp_path / "p.jsonl").read_text().splitlines()]
    expected: dict[str, list[dict[str, Any]]] = {}
    for row in rows:  # what JSON Lines holds, split as MCAP topics are
        for part in row.get("sub_packages", [row]):
            body = {k: v for k, v in part.items() if k != "package" or "sub_packages" not in row}
            expected.setdefault(f"/primary/{part['package']}", []).append({"offset": row["offset"], **body})
    assert set(messages) == set(expected) and "/primary/joint_data" in messages
    for topic, bodies in expected.items():
        assert [m for _, m in messages[topic]] == bodies
    joints = schemas["/primary/joint_data"]["properties"]["joints"]
    assert joints["type"] == "array" and joints["maxItems"] == 6
    assert joints["items"]["properties"]["q_actual"]["type"] == "number"
    state_times = {
        messages[t][0][0] for t in messages if t not in ("/primary/version_message", "/primary/text_message")
    }
    assert len(state_times) == 1  # one Robot State: its sub-packages at one time (robot_mode_data's µs)
    mode_data = messages["/primary/robot_mode_data"][0]
    version = messages["/primary/version_message"][0]
    assert mode_data[0] - version[0] == (mode_data[1]["timestamp"] - version[1]["timestamp"]) * 1000


def test_the_file_appears_complete_or_not_at_all(stream: Path, tmp_path: Path) -> None:
    target = tmp_path / "out.mcap"
    target.write_bytes(b"old")
    writer = open_writer("mcap", target)
    writer.write({"package": "text_message", "package_type": "M", "message": "x"})
    assert target.read_bytes() == b"old"  # written beside it until closed
    writer.abort()
    assert target.read_bytes() == b"old" and not list(tmp_path.glob(".out.mcap*"))
    decode_to_mcap(stream, target)
    assert target.read_bytes()[:8] == b"\x89MCAP0\r\n" and target.read_bytes()[-8:] == b"\x89MCAP0\r\n"


def test_a_capture_holds_in_mcap_what_it_holds_in_parquet(tmp_path: Path) -> None:
    """capture to MCAP against capture to Parquet: every value, logged at its packet's capture time."""
    from rtde_spec.capture.decoder import decode_to_directory
    from rtde_spec.output.topics import topic_for_table

    from .capture_files import rtde_capture, rtde_packages

    pcap = rtde_capture(tmp_path / "run.pcap", rtde_packages(500))
    decode_to_directory(pcap, tmp_path / "pq", "parquet")
    summary = decode_to_directory(pcap, tmp_path / "mc", "mcap")
    assert summary.tables and all(p.endswith(".mcap") for p in summary.paths)
    for table in summary.tables:
        (parquet,) = (tmp_path / "pq" / table).rglob("*.parquet")
        (mcap,) = (tmp_path / "mc" / table).rglob("*.mcap")
        rows = pq.read_table(parquet).to_pylist()
        messages, _ = read_mcap(mcap)
        assert list(messages) == [topic_for_table(table)]
        got = messages[topic_for_table(table)]
        assert len(got) == len(rows) > 0
        for row, (log_time, message) in zip(rows, got, strict=True):
            assert log_time == round(Fraction(row["capture_time"]) * 10**9)  # the float's time, to the ns
            for name, value in row.items():
                if name in message:
                    assert message[name] == value, (table, name)
                else:  # Parquet spreads vectors into name_0..name_5
                    base, _, index = name.rpartition("_")
                    assert message[base][int(index)] == value, (table, name)
    assert "/rtde/outputs/1" in {topic_for_table(t) for t in summary.tables}


def test_the_commands_write_mcap_by_suffix_and_format(stream: Path, tmp_path: Path) -> None:
    """decode (-o x.mcap), capture (--format mcap): the same messages the Python writer logs."""
    from .capture_files import rtde_capture, rtde_packages
    from .test_cli import cli

    recipe = tmp_path / "recipe.txt"
    recipe.write_text("\n".join(NAMES) + "\n")
    out = tmp_path / "cli.mcap"
    result = cli("decode", str(stream), "--from", "controller", "--recipe", str(recipe), "-o", str(out))
    assert result.returncode == 0, result.stderr
    messages, _ = read_mcap(out)
    assert sum(len(m) for t, m in messages.items() if t.startswith("/rtde/outputs/")) == ROWS
    pcap = rtde_capture(tmp_path / "run.pcap", rtde_packages(50))
    result = cli("capture", str(pcap), "-o", str(tmp_path / "tables"), "--format", "mcap")
    assert result.returncode == 0, result.stderr
    files = list((tmp_path / "tables").rglob("*.mcap"))
    assert files and all(read_mcap(f)[0] for f in files)


def test_a_capture_time_is_logged_at_the_nanosecond_its_float_holds() -> None:
    """`capture_time * 1e9` is rounded to a multiple of 256 ns at today's epoch: a log time was up
    to 128 ns off the time the float holds (on top of the float's own 119 ns), so only 8 of 3,000
    MCAP log times of a real dumpcap capture were the frame's nanosecond. Whole seconds and the
    fraction are now converted apart."""
    import random

    import numpy as np

    from rtde_spec.output.topics import Clock

    rng = random.Random(5)
    times = [1_795_765_736 + rng.random() * 1e6 for _ in range(1000)]
    exact = [round(Fraction(t) * 10**9) for t in times]
    assert Clock().many({"capture_time": np.array(times)}, 1.0).tolist() == exact
    clock = Clock()
    assert [clock.capture(t) for t in times] == exact
    # past int64's nanoseconds (the year 2261): the time before, as for a row without one
    assert Clock().many({"capture_time": np.array([5.0, 1e300])}, 1.0).tolist() == [5 * 10**9] * 2
