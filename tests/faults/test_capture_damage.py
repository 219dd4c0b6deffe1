"""Issue 18, point 4: a damaged input is never a silent success.

Each capture keeps what decodes; the CLI prints a summary line per file on stderr and
exits 3 (0 with --lenient). The damage is made with struct on files dpkt wrote.
"""

from __future__ import annotations

import struct
from pathlib import Path

import pyarrow.dataset as ds

from rtde_spec.capture.decoder import decode_to_directory

from ..capture_files import pcap_records, rtde_capture, rtde_packages, run_capture

SETUP_FRAMES = 8  # handshake (2) and the setup exchange (6) before the data packages


def rows(folder: Path) -> list[int]:
    table = ds.dataset(folder / "rtde_outputs_1", format="parquet", partitioning="hive").to_table()
    return [round(t / 0.002) for t in table.column("timestamp").to_pylist()]


def test_a_truncated_pcap_keeps_what_precedes_the_cut_and_exits_3(tmp_path: Path) -> None:
    path = rtde_capture(tmp_path / "cut.pcap", rtde_packages(300))
    offset, caplen = pcap_records(path)[SETUP_FRAMES + 200]
    path.write_bytes(path.read_bytes()[: offset + 16 + caplen // 2])  # cut inside record 200
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert rows(tmp_path / "out") == list(range(200))
    line = next(x for x in result.stderr.splitlines() if x.startswith("summary"))
    assert str(path) in line and "1 truncated records" in line and "206 packages" in line
    assert f"cut off at byte {offset}" in result.stderr


def test_a_record_length_of_2_to_the_31_is_skipped_and_reported_with_the_file_name(tmp_path: Path) -> None:
    """Reading goes on at the next whole record: only the damaged record's package is lost."""
    path = rtde_capture(tmp_path / "huge.pcap", rtde_packages(300))
    data = bytearray(path.read_bytes())
    offset, caplen = pcap_records(path)[SETUP_FRAMES + 150]
    struct.pack_into("<I", data, offset + 8, 1 << 31)  # the captured length of record 150
    path.write_bytes(bytes(data))
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert rows(tmp_path / "out") == [i for i in range(300) if i != 150]
    skipped = f"1 records whose length cannot be one: {16 + caplen} bytes skipped to the next whole record"
    assert skipped in result.stderr and str(path) in result.stderr
    piped = run_capture("-", "-o", str(tmp_path / "piped"), cwd=tmp_path, stdin=bytes(data))  # a pipe
    assert piped.returncode == 3 and skipped in piped.stderr, piped.stderr
    assert rows(tmp_path / "piped") == [i for i in range(300) if i != 150]


def test_a_record_claiming_past_the_end_of_the_file_is_a_cut_off_record(tmp_path: Path) -> None:
    path = rtde_capture(tmp_path / "last.pcap", rtde_packages(100))
    data = bytearray(path.read_bytes())
    offset, _ = pcap_records(path)[-1]
    struct.pack_into("<I", data, offset + 8, 1400)  # within the snap length (1500), past the end
    path.write_bytes(bytes(data))
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert rows(tmp_path / "out") == list(range(99))
    assert f"cut off at byte {offset} (it claims 1416 bytes)" in result.stderr


def test_a_pcapng_timestamp_of_2_to_the_62_keeps_its_row_in_date_unknown(tmp_path: Path) -> None:
    """Today: `error: [Errno 75] Value too large for defined data type`, no file name, nothing kept."""
    path = rtde_capture(tmp_path / "time.pcapng", rtde_packages(100), fmt="pcapng")
    data = bytearray(path.read_bytes())
    pos, epbs = 0, []
    while pos + 8 <= len(data):
        btype, length = struct.unpack_from("<II", data, pos)
        if btype == 6:
            epbs.append(pos)
        pos += length
    stamp = 1 << 62
    struct.pack_into("<II", data, epbs[SETUP_FRAMES + 50] + 12, stamp >> 32, stamp & 0xFFFFFFFF)
    path.write_bytes(bytes(data))
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert "Errno" not in result.stderr and "1 frames with an impossible capture time" in result.stderr
    table = ds.dataset(tmp_path / "out" / "rtde_outputs_1", format="parquet", partitioning="hive").to_table()
    times = dict(zip(rows(tmp_path / "out"), table.column("capture_time").to_pylist(), strict=True))
    assert sorted(times) == list(range(100)) and times[50] == stamp * 1e-6  # kept, with its time


def test_a_stream_that_ends_inside_a_package_exits_3_and_lenient_exits_0(tmp_path: Path) -> None:
    packages = rtde_packages(50)
    packages[-1] = packages[-1][:-9]  # the capture stops 9 bytes short of the last package's end
    path = rtde_capture(tmp_path / "end.pcap", packages)
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert "ends inside a controller package (55 bytes of it)" in result.stderr
    assert rows(tmp_path / "out") == list(range(49))
    lenient = run_capture(str(path), "-o", str(tmp_path / "out2"), "--lenient", cwd=tmp_path)
    assert lenient.returncode == 0 and "summary" in lenient.stderr and "damaged" in lenient.stderr


def test_a_pcapng_block_that_cannot_be_one_is_skipped_not_the_file_nor_the_run(tmp_path: Path) -> None:
    """A block length that is no block (not a multiple of 4) in the middle of the file: only
    its package is lost, the next file is decoded, exit 3 (was 2, and nothing after it)."""
    bad = rtde_capture(tmp_path / "a" / "bad.pcapng", rtde_packages(80), fmt="pcapng")
    data = bytearray(bad.read_bytes())
    pos, blocks = 0, []
    while pos + 8 <= len(data):
        length = struct.unpack_from("<I", data, pos + 4)[0]
        blocks.append(pos)
        pos += length
    where = blocks[-30]  # the block of package 50
    length = struct.unpack_from("<I", data, where + 4)[0]
    struct.pack_into("<I", data, where + 4, 13)
    bad.write_bytes(bytes(data))
    good = rtde_capture(tmp_path / "b" / "good.pcapng", rtde_packages(20), fmt="pcapng")
    result = run_capture(str(bad), str(good), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert f"1 records whose length cannot be one: {length} bytes skipped" in result.stderr
    assert sorted(rows(tmp_path / "out")) == sorted([*(i for i in range(80) if i != 50), *range(20)])
    summary = decode_to_directory(good, tmp_path / "one")
    assert not summary.damage() and "ok" in summary.line()


def test_an_undamaged_capture_exits_0_with_its_summary(tmp_path: Path) -> None:
    path = rtde_capture(tmp_path / "fine.pcap", rtde_packages(40))
    result = run_capture(str(path), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert f"summary {path}: ok: {SETUP_FRAMES + 40} frames, 46 packages, 0 gaps" in result.stderr


def test_a_connection_keeps_its_first_problems_word_for_word_and_counts_the_rest() -> None:
    from rtde_spec.capture.protocols.base import MAX_PROBLEMS, Problems

    problems = Problems()
    for i in range(MAX_PROBLEMS + 250):
        problems.append(f"package {i}: bad")
    assert len(problems) == MAX_PROBLEMS and problems.more == 250
    assert problems.lines()[-1] == "... 250 more problems of this connection, not listed"
