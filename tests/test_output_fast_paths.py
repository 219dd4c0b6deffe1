"""The fast paths behind streaming output give what the plain paths give.

Framing in place (views of the input, no copy), JSON Lines from numpy columns
without Python objects, the background file writer, and Parquet's per-column
compression: each checked against the straightforward way or the file read back.
"""

from __future__ import annotations

import io
import itertools
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import orjson
import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rtde_spec import RecipeCodec, StreamDecoder, build, open_writer
from rtde_spec.output.background import BackgroundStream
from rtde_spec.output.jsonlines import fits, formatter
from rtde_spec.wire.framing import PackageFramer
from tests.budget import examples

NAMES = ["timestamp", "actual_q", "robot_mode", "output_bit_register_64", "actual_digital_input_bits"]
CODEC = RecipeCodec.for_names(NAMES, "output")
RUN = (CODEC.package_size, CODEC.encode_package(
    {"timestamp": 0.0, "actual_q": (0.0,) * 6, "robot_mode": 0, "output_bit_register_64": False,
     "actual_digital_input_bits": 0}, recipe_id=1)[:3])  # fmt: skip
TEXT = build("text_message", message="hello", source="ctl", warning_level=3)


def data_packages(count: int, start: int = 0) -> bytes:
    return b"".join(
        CODEC.encode_package(
            {"timestamp": i * 0.002, "actual_q": tuple(i + j / 8 for j in range(6)), "robot_mode": i % 8,
             "output_bit_register_64": i % 3 == 0, "actual_digital_input_bits": i * 2654435761 % 2**64},
            recipe_id=1,
        )
        for i in range(start, start + count)
    )  # fmt: skip


REPLY = build("request_protocol_version_reply", accepted=True)
STREAM = REPLY + data_packages(40) + TEXT + data_packages(25, 40)


def frame(pieces: list[bytes | bytearray]) -> list[tuple[int, bytes]]:
    """(offset, bytes) of every package; runs (several data packages in one item) split up."""
    framer = PackageFramer()
    out = []
    for piece in pieces:
        for offset, chunk in framer.feed(piece, RUN):
            size = int.from_bytes(chunk[:2], "big")
            out += [(offset + k, bytes(chunk[k : k + size])) for k in range(0, len(chunk), size)]
    framer.close()
    return out


@settings(max_examples=examples(60), deadline=None)
@given(st.lists(st.integers(0, len(STREAM)), max_size=12))
def test_framing_in_place_equals_framing_a_copy_at_any_cut(cuts: list[int]) -> None:
    bounds = [0, *sorted(cuts), len(STREAM)]
    pieces = [STREAM[a:b] for a, b in itertools.pairwise(bounds)]
    as_bytes = frame(pieces)  # runs come out as views of the input where they can
    as_bytearray = frame([bytearray(p) for p in pieces])  # always copied through the buffer
    assert as_bytes == as_bytearray
    assert b"".join(chunk for _, chunk in as_bytes) == STREAM
    offsets = [offset for offset, _ in as_bytes]
    assert offsets == sorted(offsets) and offsets[0] == 0 and len(as_bytes) == 67


def test_a_run_framed_in_place_is_a_view_and_a_bytearray_run_is_a_copy() -> None:
    data = data_packages(10)
    [(_, chunk)] = PackageFramer().feed(data, RUN)
    assert isinstance(chunk, memoryview) and chunk.obj is data  # no copy of immutable input
    mutable = bytearray(data)
    [(_, copied)] = PackageFramer().feed(mutable, RUN)
    mutable[:] = bytes(len(mutable))
    assert copied == data  # the caller may reuse its buffer


@pytest.mark.parametrize("chunk", [1, 500, CODEC.package_size + 1, 4096, len(STREAM)])
def test_stream_decoder_values_equal_decoding_the_packages_whole(chunk: int) -> None:
    decoder = StreamDecoder("controller", codec=CODEC)
    arrays, texts = [], []
    for start in range(0, len(STREAM), chunk):
        for item in decoder.feed(STREAM[start : start + chunk]):
            if hasattr(item, "array"):
                arrays.append(item.array)
            else:
                texts.append(item.message.NAME)
    decoder.close()
    got = np.concatenate(arrays)
    want = np.concatenate([CODEC.decode_many(data_packages(40)), CODEC.decode_many(data_packages(25, 40))])
    assert texts == ["request_protocol_version_reply", "text_message"] and got.tobytes() == want.tobytes()


def row_dicts(columns: dict[str, np.ndarray]) -> bytes:
    """The plain way: Python values, one dict per row, orjson per row."""
    names = list(columns)
    lists = [columns[n].astype(columns[n].dtype.newbyteorder("=")).tolist() for n in names]
    return b"".join(orjson.dumps(dict(zip(names, v, strict=True))) + b"\n" for v in zip(*lists, strict=True))


def test_json_lines_from_columns_equal_json_of_row_dicts_for_every_kind() -> None:
    rows = 7
    columns = {
        "f8": np.array([0.1, -0.0, math.nan, math.inf, -math.inf, 1e308, 5e-324], dtype=">f8"),
        "vec": np.arange(rows * 3, dtype="<f8").reshape(rows, 3) / 7,
        "i1": np.array([-128, 127, 0, -1, 5, 6, 7], dtype="i1"),
        "u8": np.array([2**64 - 1, 0, 1, 2**63, 3, 4, 5], dtype=">u8"),
        'quote "and" 100%': np.array([1, 2, 3, 4, 5, 6, 7], dtype=">u4"),
        "bits": np.array([[True, False]] * rows),
        "i8vec": np.array([[-(2**63), 2**63 - 1]] * rows, dtype=">i8"),
        "u1": np.arange(rows, dtype="u1"),
    }
    assert fits(columns)
    lines = formatter()
    assert lines(columns) == row_dicts(columns)
    one = {"only": np.array([1.5, 2.5])}
    assert lines(one) == row_dicts(one)  # a new set of columns: planned anew
    assert lines({"only": np.array([], dtype=float)}) == b""


def test_json_lines_of_a_real_recipe_equal_row_dicts() -> None:
    array = CODEC.decode_many(data_packages(300))
    columns = {name: array[name] for name in CODEC.names}
    assert formatter()(columns) == row_dicts(columns)


class Failing(io.BytesIO):
    def write(self, block: object) -> int:
        raise OSError(28, "No space left on device")


def test_background_stream_keeps_order_and_raises_the_writers_error_in_the_caller() -> None:
    target = io.BytesIO()
    stream = BackgroundStream(target)
    blocks = [bytes([i % 256]) * size for i, size in enumerate([3, 2 << 20, 10, 1, 3 << 20, 7] * 3)]
    for block in blocks:
        stream.write(block)
    stream.flush()
    assert target.getvalue() == b"".join(blocks)
    stream.close()
    broken = BackgroundStream(Failing())
    with pytest.raises(OSError, match="No space left"):
        broken.write(b"x" * (2 << 20))
        broken.flush()
    broken.close()


def test_parquet_compresses_only_the_columns_that_pay(tmp_path: Path) -> None:
    array = CODEC.decode_many(data_packages(500))
    path = tmp_path / "out.parquet"
    writer = open_writer("parquet", path)
    writer.write_columns({name: array[name] for name in CODEC.names})
    writer.close()
    meta = pq.ParquetFile(path).metadata.row_group(0)
    codecs = {meta.column(i).path_in_schema: meta.column(i).compression for i in range(meta.num_columns)}
    assert codecs["actual_q_0"] == "UNCOMPRESSED" and codecs["timestamp"] == "UNCOMPRESSED"
    assert codecs["robot_mode"] == "SNAPPY" and codecs["output_bit_register_64"] == "SNAPPY"
    table = pq.read_table(path)
    assert table.column("actual_q_5").to_pylist() == [i + 5 / 8 for i in range(500)]
    bits = [i * 2654435761 % 2**64 for i in range(500)]
    assert table.column("actual_digital_input_bits").to_pylist() == bits


def test_parquet_of_numbers_and_text_neither_imports_pandas_nor_changes_values(tmp_path: Path) -> None:
    """Arrow arrays come from numpy buffers: pandas (50 MB, a quarter second) stays unloaded."""
    code = f"""
import sys, numpy as np
from rtde_spec import open_writer
writer = open_writer("parquet", {str(tmp_path / "t.parquet")!r})
writer.write_columns({{"connection": np.full(3, "10.0.0.2:5-x"), "robot": np.array(["a", "é", ""]),
                      "flag": np.array([True, False, True]), "q": np.array([[1.5, 2.5]] * 3)}})
writer.close()
print("pandas" in sys.modules)
"""
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False"
    table = pq.read_table(tmp_path / "t.parquet")
    assert table.column("robot").to_pylist() == ["a", "é", ""]
    assert table.column("connection").to_pylist() == ["10.0.0.2:5-x"] * 3
    assert (
        table.column("flag").to_pylist() == [True, False, True]
        and table.column("q_1").to_pylist() == [2.5] * 3
    )


@settings(max_examples=examples(60), deadline=None)
@given(st.lists(st.text(max_size=6), max_size=20), st.booleans())
def test_text_columns_to_arrow_as_pyarrow_makes_them(values: list[str], constant: bool) -> None:
    """Text columns (the one-value fast path included) hold what pyarrow's own conversion holds."""
    import pyarrow as pa

    from rtde_spec.output.tables import arrow_array

    if constant and values:
        values = [values[0]] * len(values)
    column = np.array(values, dtype=str) if values else np.array([], dtype="U1")
    got = arrow_array(column)
    got.validate(full=True)
    assert got.type == pa.string() and got.to_pylist() == [str(v) for v in column.tolist()]


def _client_with_recipe() -> Any:
    """A sans-I/O client core that has negotiated protocol 2 and set up NAMES as its outputs."""
    from rtde_spec.rtde.client_protocol import ClientProtocol

    core = ClientProtocol()
    core.request_protocol_version(2)
    core.receive(build("request_protocol_version_reply", accepted=True))
    core.setup_outputs(NAMES, 125.0)
    types = [core.catalogue.get(n, "output").type for n in NAMES]
    core.receive(build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types))
    return core


@settings(max_examples=examples(80), deadline=None)
@given(st.lists(st.integers(1, 400), max_size=12))
def test_client_core_gives_the_same_events_whatever_the_reads(cuts: list[int]) -> None:
    """One package per read (the per-package path), several, or split anywhere: the same
    records and text in the same order, and the stream offset counts every byte."""
    from rtde_spec.rtde.client_protocol import DataRun, Text

    stream = data_packages(3) + TEXT + data_packages(4, start=3)
    reference = _client_with_recipe()
    size = CODEC.package_size
    whole = [stream[:size], stream[size : 2 * size], stream[2 * size : 3 * size], stream[3 * size :]]

    def events(core: Any, reads: list[bytes]) -> list[Any]:
        out: list[Any] = []
        for read in reads:
            for event in core.receive(read):
                out += event.records if isinstance(event, DataRun) else [event]
        return out

    before = reference.framer.offset
    expected = events(reference, whole)  # the first three reads: one whole data package each
    assert reference.framer.offset - before == len(stream) and reference.framer.pending == 0
    assert [isinstance(e, Text) for e in expected] == [False] * 3 + [True] + [False] * 4
    assert [e.timestamp for e in expected if not isinstance(e, Text)] == [i * 0.002 for i in range(7)]
    runs = _client_with_recipe()  # reads of several whole data packages each, as a batched client
    start = runs.framer.offset
    runs_reads = [stream[: 3 * size], TEXT, stream[3 * size + len(TEXT) :]]
    assert events(runs, runs_reads) == expected and runs.framer.offset - start == len(stream)
    bounds = sorted({min(c, len(stream)) for c in itertools.accumulate(cuts)} | {0, len(stream)})
    core = _client_with_recipe()
    start = core.framer.offset
    assert events(core, [stream[a:b] for a, b in itertools.pairwise(bounds)]) == expected
    assert core.framer.offset - start == len(stream) and core.framer.pending == 0


def test_a_read_the_size_of_whole_packages_that_is_not_only_data_takes_the_general_path() -> None:
    """A batched client decodes a read of N package sizes before it checks the leads; a read of
    that length holding a text message (or a package of another recipe) is then framed the
    general way, and no record of the first decode survives."""
    from rtde_spec.rtde.client_protocol import DataRun, Text

    size = CODEC.package_size
    stream = data_packages(1) + TEXT + data_packages(3, start=1)
    cut = 2 * size  # the first read: one package, the text, and a piece of the next package
    core = _client_with_recipe()
    got: list[Any] = []
    for read in (stream[:cut], stream[cut:]):
        for event in core.receive(read):
            got += event.records if isinstance(event, DataRun) else [event]
    assert [type(e).__name__ for e in got] == ["Record", "Text", "Record", "Record", "Record"]
    assert isinstance(got[1], Text)
    assert [e.timestamp for e in got if not isinstance(e, Text)] == [i * 0.002 for i in range(4)]
    other = bytearray(data_packages(2))
    other[3] = 9  # recipe id 9 in the first package: not this client's recipe
    with pytest.raises(Exception, match="recipe"):
        _client_with_recipe().receive(bytes(other))


@settings(max_examples=examples(80), deadline=None)
@given(st.integers(0, 5), st.integers(0, 3), st.integers(0, 255))
def test_a_damaged_lead_in_a_batched_read_ends_as_in_reads_of_one_package(
    package: int, byte: int, value: int
) -> None:
    """One lead byte (size, type, recipe id) changed in one of six packages: a read of all
    six (decoded first, checked after) ends as six reads of one package each — no record
    of a damaged package, the same records before it, then an error (which one may differ:
    a whole read can find the next package unframeable before the damaged one is judged),
    or the same records when there is no error (all six when the byte did not change; fewer
    when a larger size makes the framer wait for more)."""
    from rtde_spec.errors import RtdeSpecError
    from rtde_spec.rtde.client_protocol import DataRun

    size = CODEC.package_size
    stream = bytearray(data_packages(6))
    unchanged = stream[package * size + byte] == value
    stream[package * size + byte] = value

    def outcome(reads: list[bytes]) -> tuple[list[Any], str | None]:
        core, got = _client_with_recipe(), []
        try:
            for read in reads:
                for event in core.receive(read):
                    got += event.records if isinstance(event, DataRun) else [event]
        except RtdeSpecError as exc:
            return got, type(exc).__name__
        return got, None

    whole = outcome([bytes(stream)])
    single = outcome([bytes(stream[i : i + size]) for i in range(0, len(stream), size)])
    assert (whole[1] is None) == (single[1] is None)
    if whole[1] is None:
        assert whole[0] == single[0] and (len(whole[0]) == 6 or not unchanged)
    else:
        assert whole[0] == single[0][: len(whole[0])] and len(whole[0]) <= package


@pytest.mark.parametrize("reads", ["one per package", "whole batch", "cut mid-package"])
def test_a_core_that_wants_no_records_frames_counts_and_checks_as_one_that_does(reads: str) -> None:
    """`want_records = False` (a client with only raw callbacks, as the recorder): the same
    packages, counted alike and the same bytes; no record made; a package of another
    recipe is still refused."""
    from rtde_spec.rtde.client_protocol import DataRun

    size = CODEC.package_size
    stream = data_packages(5) + TEXT + data_packages(4, start=5)
    if reads == "one per package":
        cuts = [size * i for i in range(6)] + [5 * size + len(TEXT) + size * i for i in range(5)]
    elif reads == "whole batch":
        cuts = [0, 5 * size, 5 * size + len(TEXT), len(stream)]
    else:
        cuts = [0, 7, 2 * size + 3, 5 * size + 2, len(stream) - 9, len(stream)]
    chunks = [stream[a:b] for a, b in itertools.pairwise(cuts)]

    def run(want: bool) -> tuple[list[int], list[bytes], int]:
        core = _client_with_recipe()
        core.want_records = want
        counts, raws, made = [], [], 0
        for chunk in chunks:
            for event in core.receive(chunk):
                if isinstance(event, DataRun):
                    counts.append(event.count)
                    raws += event.packages()
                    made += len(event.records)
        return counts, raws, made

    with_records, without = run(True), run(False)
    assert with_records[:2] == without[:2] and sum(without[0]) == 9 and len(without[1]) == 9
    assert with_records[2] == 9 and without[2] == 0
    other = bytearray(data_packages(2))
    other[3] = 9  # recipe id 9: not this client's recipe
    core = _client_with_recipe()
    core.want_records = False
    with pytest.raises(Exception, match="recipe"):
        core.receive(bytes(other))


def test_a_background_written_output_appears_whole_at_close_or_not_at_all(tmp_path: Path) -> None:
    """The decoder's writing thread writes into the hidden part file; the name shows the old
    file until close, and an aborted run (or one whose writes fail) leaves it as it was."""
    out = tmp_path / "decoded.jsonl"
    out.write_bytes(b"the previous run\n")
    array = CODEC.decode_many(data_packages(3000))
    columns = {name: array[name] for name in CODEC.names}
    writer = open_writer("jsonl", out, background=True)
    writer.write_columns(columns)
    writer.flush()  # in the part file, not yet under its name
    assert out.read_bytes() == b"the previous run\n"
    writer.abort()
    assert out.read_bytes() == b"the previous run\n"
    assert [p.name for p in tmp_path.iterdir()] == ["decoded.jsonl"]
    writer = open_writer("jsonl", out, background=True)
    real, writer.stream.raw = writer.stream.raw, Failing()  # type: ignore[attr-defined]  # the disk fills up
    with pytest.raises(OSError, match="No space left"):
        writer.write_columns({n: np.repeat(c, 200, axis=0) for n, c in columns.items()})  # > 1 MB
        writer.close()
    with pytest.raises(OSError, match="No space left"):  # reported again: the output has a hole
        writer.close()
    real.close()
    assert out.read_bytes() == b"the previous run\n"
    assert [p.name for p in tmp_path.iterdir()] == ["decoded.jsonl"]
    writer = open_writer("jsonl", out, background=True)
    writer.write_columns(columns)
    writer.close()
    assert len(out.read_bytes().splitlines()) == 3000
