"""`decode` of hex as people copy it: dumps with offsets, C arrays, escaped strings.

Before, a dump file (offsets, hex, the ASCII column) was taken for binary: "expected 12336
bytes" from the text's own characters. A dump of plain hex digits was worse: its offsets were
read as package bytes. The dumps below are what the tools printed for STREAM.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec import build
from rtde_spec.cli.hex_dumps import from_hex_forms
from rtde_spec.errors import RtdeSpecError

from .test_cli import cli

STREAM = (
    build("request_protocol_version", protocol_version=2)
    + build("get_urcontrol_version")
    + build(
        "setup_outputs_v2", output_frequency=125.0, variable_names=["timestamp", "actual_q", "robot_mode"]
    )
    + build("start")
)
XXD = """\
00000000: 0005 5600 0200 0376 0028 4f40 5f40 0000  ..V....v.(O@_@..
00000010: 0000 0074 696d 6573 7461 6d70 2c61 6374  ...timestamp,act
00000020: 7561 6c5f 712c 726f 626f 745f 6d6f 6465  ual_q,robot_mode
00000030: 0003 53                                  ..S
"""
HEXDUMP_C = """\
00000000  00 05 56 00 02 00 03 76  00 28 4f 40 5f 40 00 00  |..V....v.(O@_@..|
00000010  00 00 00 74 69 6d 65 73  74 61 6d 70 2c 61 63 74  |...timestamp,act|
00000020  75 61 6c 5f 71 2c 72 6f  62 6f 74 5f 6d 6f 64 65  |ual_q,robot_mode|
00000030  00 03 53                                          |..S|
00000033
"""
WIRESHARK = """\
0000   00 05 56 00 02 00 03 76 00 28 4f 40 5f 40 00 00   ..V....v.(O@_@..
0010   00 00 00 74 69 6d 65 73 74 61 6d 70 2c 61 63 74   ...timestamp,act
0020   75 61 6c 5f 71 2c 72 6f 62 6f 74 5f 6d 6f 64 65   ual_q,robot_mode
0030   00 03 53                                          ..S
"""
STARRED = """\
00000000  00 00 00 00 00 00 00 00  00 00 00 00 00 00 00 00  |................|
*
00000020  00 00 00 00 00 00 00 00  00 05 56 00 02           |..........V..|
0000002d
"""


@pytest.mark.parametrize("dump", [XXD, HEXDUMP_C, WIRESHARK, WIRESHARK.replace("\n", "\r\n")])
def test_dumps_of_xxd_hexdump_and_wireshark_give_the_bytes(dump: str) -> None:
    assert from_hex_forms(dump) == STREAM


def test_hexdump_s_star_is_the_line_above_repeated_up_to_the_next_offset() -> None:
    assert from_hex_forms(STARRED) == bytes(40) + b"\x00\x05V\x00\x02"


def test_c_arrays_and_escaped_strings_give_the_bytes_and_plain_hex_is_no_form() -> None:
    assert from_hex_forms("0x00, 0x05, 0x56,\n 0x00, 0x02") == b"\x00\x05V\x00\x02"
    assert from_hex_forms("\\x00\\x05\\x56\\x00\\x02") == b"\x00\x05V\x00\x02"
    assert from_hex_forms("00 05 56 00 02") is None  # plain hex: read as it always was
    assert from_hex_forms("0005 5600 02") is None
    assert from_hex_forms("00045601") is None and from_hex_forms("0004  5601") is None
    assert from_hex_forms("0000  5601") == b"V\x01"


def test_a_line_missing_or_cut_is_named_not_decoded() -> None:
    lines = WIRESHARK.splitlines()
    with pytest.raises(RtdeSpecError, match=r"line 1: 16 bytes, but the next line's offset is 32 bytes on"):
        from_hex_forms("\n".join([lines[0], lines[2], lines[3]]))
    with pytest.raises(RtdeSpecError, match="line 4: offset 0x10 where 0x30 was due"):
        from_hex_forms("\n".join([lines[0], lines[1], lines[2], lines[1]]))
    with pytest.raises(RtdeSpecError, match="line 1: 5 bytes, but the next line's offset is 16 bytes on"):
        from_hex_forms("0000   00 05 56 00 02\n0010   00 03\n")


def test_decode_reads_a_dump_file_a_dump_on_the_command_line_and_a_c_array(tmp_path: Path) -> None:
    for name, text in (("xxd.txt", XXD), ("hexdump.txt", HEXDUMP_C), ("wireshark.txt", WIRESHARK)):
        path = tmp_path / name
        path.write_text(text)
        done = cli("decode", str(path), "--from", "client", "--jsonl")
        assert done.returncode == 0, done.stderr
        packages = [line.split('"package":"')[1].split('"')[0] for line in done.stdout.splitlines()]
        assert packages == ["request_protocol_version", "get_urcontrol_version", "setup_outputs_v2", "start"]
    for arg in ("0000   00 05 56 00 02   ..V..", "0x00,0x05,0x56,0x00,0x02"):
        done = cli("decode", arg, "--from", "client", "--jsonl")
        assert done.returncode == 0 and '"protocol_version":2' in done.stdout, done.stderr


def test_a_long_dump_reads_in_time_linear_in_its_length() -> None:
    """Each line looked for its successor in a copy of every line after it: a 2 MB hexdump took
    minutes. Eight times the dump now takes about eight times as long (quadratic was 64)."""
    import time

    def dump(data: bytes) -> str:
        rows = [data[i : i + 16] for i in range(0, len(data), 16)]
        return "".join(f"{16 * n:08x}  {row.hex(' ')}\n" for n, row in enumerate(rows)) + f"{len(data):08x}\n"

    small, large = bytes(range(256)) * 160, bytes(range(256)) * 1280  # 40 kB, 320 kB
    times = []
    for data in (small, large):
        text = dump(data)
        start = time.perf_counter()
        assert from_hex_forms(text) == data
        times.append(time.perf_counter() - start)
    assert times[1] < 24 * times[0] + 0.05, times
