"""Captures compressed whole, as Wireshark reads them (`.pcap.gz`, `.pcapng.zst`, `.lz4`, ...).

Before: `capture x.pcapng.gz` said "not a pcap or pcapng file (magic 1f8b0808)" and exit 2,
naming no cause and no remedy, though Wireshark reads the file as it is. Now gzip, xz and bzip2
(standard library), zstd and lz4 (the `zstandard`, `lz4` packages, installed with the test
extra through mcap) read as the plain file; a reader that is not installed is a usage error
naming the file, the package and the command that decompresses it; a compressed file cut short
keeps what came before, says where it ends and exits 3.
"""

from __future__ import annotations

import bz2
import lzma
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.errors import UsageError
from tests.capture_files import Conversation, rtde_packages, rtde_setup, run_capture, write


def plain(tmp_path: Path, count: int = 400) -> Path:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    for package in rtde_packages(count):
        conv.send("server", package)
    return write(tmp_path / "plain.pcapng", [conv], "pcapng")


def rows(path: Path) -> dict[str, list[dict[str, object]]]:
    return {name: table.to_pylist() for name, table in capture_tables(path).items()}


def gzipped(source: Path) -> Path:
    """With the gzip tool, as users make them (its header holds the name and time)."""
    subprocess.run(["gzip", "-k", str(source)], check=True)
    return source.with_name(source.name + ".gz")


def compressed(source: Path, kind: str) -> Path:
    data = source.read_bytes()
    if kind == "zst":
        import zstandard

        packed = zstandard.ZstdCompressor().compress(data)
    elif kind == "lz4":
        import lz4.frame

        packed = lz4.frame.compress(data)
    else:
        packed = lzma.compress(data) if kind == "xz" else bz2.compress(data)
    target = source.with_name(f"{source.name}.{kind}")
    target.write_bytes(packed)
    return target


@pytest.mark.parametrize("kind", ["gz", "zst", "lz4", "xz", "bz2"])
def test_a_compressed_capture_gives_the_plain_ones_rows(tmp_path: Path, kind: str) -> None:
    source = plain(tmp_path)
    packed = gzipped(source) if kind == "gz" else compressed(source, kind)
    assert packed.read_bytes()[:4] != source.read_bytes()[:4]
    expected = rows(source)
    assert len(expected["rtde_outputs_1"]) == 400
    assert rows(packed) == expected


def test_a_compressed_capture_cut_short_keeps_what_came_before_and_says_so(tmp_path: Path) -> None:
    packed = gzipped(plain(tmp_path, 3000))
    cut = tmp_path / "cut.pcapng.gz"
    cut.write_bytes(packed.read_bytes()[: packed.stat().st_size // 2])
    done = run_capture(str(cut), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 3, done.stderr
    assert "the compressed file ends early or is corrupt after" in done.stderr
    kept = int(done.stdout.split("rtde_outputs_1 (")[1].split(" ")[0])
    assert 0 < kept < 3000


def test_a_compressed_capture_without_its_reader_names_the_package_and_the_command(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    packed = compressed(plain(tmp_path, 5), "zst")
    monkeypatch.setitem(sys.modules, "zstandard", None)  # as where it is not installed
    with pytest.raises(UsageError) as raised:
        capture_tables(packed)
    message = str(raised.value)
    assert str(packed) in message and "pip install zstandard" in message and "zstd -d" in message


@pytest.mark.skipif(shutil.which("gzip") is None, reason="no gzip tool")  # Debian's base system has it
def test_the_cli_reads_a_gzipped_capture_whole(tmp_path: Path) -> None:
    packed = gzipped(plain(tmp_path, 50))
    done = run_capture(str(packed), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "rtde_outputs_1 (50 rows)" in done.stdout
    (written,) = (tmp_path / "out" / "rtde_outputs_1").rglob("*.parquet")
    assert written.name.startswith("plain-")  # named as the capture, not "plain.pcapng-"


def test_gzip_members_one_after_another_and_zeros_after_them_read_as_the_gzip_module_reads_them(
    tmp_path: Path,
) -> None:
    """`cat a.gz b.gz` (and pigz) makes a file of several members; some tools pad with zeros. The
    zlib reader (1.4x less CPU than the gzip module) gives what the gzip module gives."""
    import gzip

    from rtde_spec.capture.reading.compressed import GzipMembers

    source = plain(tmp_path, 2000)
    data = source.read_bytes()
    thirds = [data[: len(data) // 3], data[len(data) // 3 : 2 * len(data) // 3], data[2 * len(data) // 3 :]]
    packed = b"".join(gzip.compress(part, compresslevel=1) for part in thirds) + b"\0" * 100
    members = tmp_path / "members.pcapng.gz"
    members.write_bytes(packed)
    with open(members, "rb") as f:
        reader, pieces = GzipMembers(f), []
        reader.STEP = 4096  # member ends and zeros across reads
        while piece := reader.read1(10_000):
            pieces.append(piece)
    assert b"".join(pieces) == gzip.decompress(packed) == data
    assert rows(members) == rows(source)


def test_bytes_after_a_gzip_member_that_are_no_member_end_the_capture_there(tmp_path: Path) -> None:
    """As the gzip module refuses them: what came before is decoded, the end is reported (exit 3)."""
    import gzip

    data = plain(tmp_path, 3000).read_bytes()
    bad = tmp_path / "trailing.pcapng.gz"
    bad.write_bytes(gzip.compress(data[: len(data) // 2]) + b"not gzip at all")
    done = run_capture(str(bad), "-o", str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 3, done.stderr
    assert "the compressed file ends early or is corrupt after" in done.stderr
    kept = int(done.stdout.split("rtde_outputs_1 (")[1].split(" ")[0])
    assert 0 < kept < 3000
