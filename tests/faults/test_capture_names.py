"""Issue 18, point 5: same-named inputs never overwrite each other; a re-run replaces its own only."""

from __future__ import annotations

from pathlib import Path

import pyarrow.dataset as ds

from ..capture_files import rtde_capture, rtde_packages, run_capture


def outputs(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_a_x_and_b_x_keep_both_and_a_rerun_replaces_only_its_own(tmp_path: Path) -> None:
    a = rtde_capture(tmp_path / "a" / "x.pcap", rtde_packages(30))
    b = rtde_capture(tmp_path / "b" / "x.pcap", rtde_packages(70))
    out = tmp_path / "out"
    result = run_capture(str(a), str(b), "-o", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    table = ds.dataset(out / "rtde_outputs_1", format="parquet", partitioning="hive").to_table()
    assert table.num_rows == 100  # 30 + 70: neither replaced the other
    first = outputs(out)
    parquet = [name for name in first if name.endswith(".parquet")]
    recipes = [name for name in first if name.startswith("recipes-")]
    assert len(parquet) == 2 * 2 and len(recipes) == 2  # two tables (outputs, setup) per input
    assert all(Path(name).name.startswith("x-") for name in parquet + [r[len("recipes-") :] for r in recipes])

    import pyarrow.parquet as pq

    by_rows = {pq.read_metadata(out / n).num_rows: out / n for n in parquet if n.startswith("rtde_outputs_1")}
    a_file, b_file = by_rows[30], by_rows[70]
    b_mtime = b_file.stat().st_mtime_ns
    a_mtime = a_file.stat().st_mtime_ns
    again = run_capture(str(a), "-o", str(out), cwd=tmp_path)  # a alone, again: the same names
    assert again.returncode == 0, again.stderr
    assert outputs(out).keys() == first.keys()  # nothing new beside: a's files replaced in place
    assert a_file.stat().st_mtime_ns != a_mtime and b_file.stat().st_mtime_ns == b_mtime
    assert not [p for p in out.rglob("*") if p.name.startswith(".") or p.name.endswith(".partial")]


def test_the_stem_is_stable_and_unique(tmp_path: Path) -> None:
    from rtde_spec.capture.tables.sink import output_stem

    a = rtde_capture(tmp_path / "a" / "x.pcap", rtde_packages(1))
    b = rtde_capture(tmp_path / "b" / "x.pcap", rtde_packages(1))
    assert output_stem(a) == output_stem(tmp_path / "a" / ".." / "a" / "x.pcap")  # the same file
    assert output_stem(a) != output_stem(b) and output_stem(a).startswith("x-")
    assert len(output_stem(a)) == len("x-") + 8


def test_outputs_appear_only_complete(tmp_path: Path) -> None:
    """While a capture is decoded its files are hidden beside their names; at the end each is
    renamed into place whole, and nothing hidden is left."""
    from rtde_spec.capture.decoder import decode_to_directory

    path = rtde_capture(tmp_path / "x.pcap", rtde_packages(300))
    out = tmp_path / "out"
    seen: list[list[str]] = []
    folder = [out]

    def progress(done: int) -> None:  # after each block of the file, before the tables close
        seen.append([p.name for p in folder[0].rglob("*") if p.is_file()])

    for fmt in ("csv", "parquet", "jsonl"):
        folder[0] = out / fmt
        summary = decode_to_directory(path, out / fmt, fmt, progress=progress)
        assert seen and seen[-1] and all(name.startswith(".") for name in seen[-1]), seen[-1]
        final = [p.name for p in (out / fmt).rglob("*") if p.is_file()]
        assert not [n for n in final if n.startswith(".")] and len(final) == len(summary.paths) + 1
