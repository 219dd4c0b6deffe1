"""Issue 18.10: `decode` keeps what it can.

Every message decoded before a fault is written, then the error (exit 1); with
--lenient, what does not decode is skipped and counted on stderr (counts, offsets)
and the run exits 0. Real subprocesses of the CLI on real files.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import rtde_spec
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.recipes.codec import RecipeCodec

ROOT = Path(rtde_spec.__file__).resolve().parents[1]
STATE_HEX = ROOT / "tests" / "data" / "ur5e_robot_state.hex"
CLI = "import sys; from rtde_spec.cli.main import main; sys.exit(main(sys.argv[1:]))"


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-c", CLI, *args], capture_output=True, text=True, timeout=300, env=env
    )


def robot_state() -> bytes:
    lines = [x for x in STATE_HEX.read_text().splitlines() if x and not x.startswith("#")]
    return bytes.fromhex("".join(lines))


def offsets(jsonl: str) -> list[int]:
    return [json.loads(line)["offset"] for line in jsonl.splitlines() if line.strip()]


RECIPE = "timestamp,actual_q"


def data_package(extra: bytes = b"") -> bytes:
    codec = RecipeCodec.for_names(RECIPE.split(","), "output", Catalogue.default())
    payload = codec.encode({"timestamp": 1.5, "actual_q": (1, 2, 3, 4, 5, 6)}) + extra
    return struct.pack(">HBB", 4 + len(payload), ord("U"), 1) + payload


def test_primary_messages_before_an_unusable_size_are_printed_then_the_error(tmp_path: Path) -> None:
    state = robot_state()
    path = tmp_path / "primary.bin"
    path.write_bytes(state + state + struct.pack(">IB", 2, 16) + state)  # size 2 < the 5-byte header
    result = cli("decode", str(path), "--protocol", "primary", "--format", "jsonl")
    assert result.returncode == 1, result.stderr
    assert offsets(result.stdout) == [0, len(state)]
    assert f"byte offset {2 * len(state)}" in result.stderr and "field size" in result.stderr
    table = cli("decode", str(path), "--protocol", "primary")
    assert table.returncode == 1
    assert table.stdout.count(f"@{len(state)}  robot_state") == 1 and "@0  robot_state" in table.stdout


def test_rtde_packages_before_an_unusable_size_are_written_then_the_error(tmp_path: Path) -> None:
    path = tmp_path / "rtde.bin"
    path.write_bytes(data_package() + b"\x00\x01U" + data_package())
    for fmt in ("jsonl", "csv"):
        result = cli("decode", str(path), "--recipe", RECIPE, "--format", fmt)
        assert result.returncode == 1, (fmt, result.stderr)
        assert "byte offset 60" in result.stderr and "cannot be framed" in result.stderr
        rows = [line for line in result.stdout.splitlines() if line.strip()]
        assert len(rows) == (2 if fmt == "csv" else 1), (fmt, result.stdout)  # csv: header + the row


def test_lenient_with_a_recipe_decodes_a_longer_payload_by_its_prefix(tmp_path: Path) -> None:
    path = tmp_path / "longer.bin"
    path.write_bytes(data_package() + data_package(b"\x00\x07") + data_package())
    result = cli("decode", str(path), "--recipe", RECIPE, "--format", "jsonl", "--lenient")
    assert result.returncode == 0, result.stderr
    rows = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["offset"] for r in rows] == [0, 60, 122]
    assert all(r["timestamp"] == 1.5 and r["actual_q"] == [1, 2, 3, 4, 5, 6] for r in rows)
    strict = cli("decode", str(path), "--recipe", RECIPE, "--format", "jsonl")
    assert strict.returncode == 1 and "longer than its recipe" in strict.stderr


def test_an_unknown_package_type_is_skipped_and_counted_with_lenient(tmp_path: Path) -> None:
    unknown = struct.pack(">HB", 5, ord("Z")) + b"ab"
    path = tmp_path / "unknown.bin"
    path.write_bytes(data_package() + unknown + data_package() + unknown)
    lenient = cli("decode", str(path), "--recipe", RECIPE, "--format", "jsonl", "--lenient")
    assert lenient.returncode == 0, lenient.stderr
    assert offsets(lenient.stdout) == [0, 65]
    assert "skipped 2 packages" in lenient.stderr and "(10 bytes)" in lenient.stderr
    assert "at byte 60:" in lenient.stderr and "at byte 125:" in lenient.stderr
    assert "unknown package type 90" in lenient.stderr
    strict = cli("decode", str(path), "--recipe", RECIPE, "--format", "jsonl")
    assert strict.returncode == 1
    assert offsets(strict.stdout) == [0]  # what came before the fault, then the error
    assert "byte offset 62" in strict.stderr and "starting at byte 60" in strict.stderr


def test_lenient_primary_skips_a_message_that_does_not_decode_and_keeps_the_rest(tmp_path: Path) -> None:
    state = robot_state()
    body = struct.pack(">QBH", 0, 1, 0) + b"\x63\n"  # a global variable of unknown type 99
    bad = struct.pack(">IB", 5 + len(body), 25) + body
    path = tmp_path / "primary.bin"
    path.write_bytes(state + bad + state)
    lenient = cli("decode", str(path), "--protocol", "primary", "--format", "jsonl", "--lenient")
    assert lenient.returncode == 0, lenient.stderr
    assert offsets(lenient.stdout) == [0, len(state) + len(bad)]
    assert "skipped 1 message " in lenient.stderr and f"at byte {len(state)}:" in lenient.stderr
    strict = cli("decode", str(path), "--protocol", "primary", "--format", "jsonl")
    assert strict.returncode == 1 and offsets(strict.stdout) == [0]


def test_lenient_ends_at_a_cut_off_package_with_a_note_not_an_error(tmp_path: Path) -> None:
    path = tmp_path / "cut.bin"
    path.write_bytes(data_package() + data_package()[:30])
    lenient = cli("decode", str(path), "--recipe", RECIPE, "--format", "jsonl", "--lenient")
    assert lenient.returncode == 0, lenient.stderr
    assert offsets(lenient.stdout) == [0]
    assert "from byte 60 on (30 bytes) was not decoded" in lenient.stderr
