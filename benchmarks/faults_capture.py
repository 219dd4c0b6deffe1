"""Capture under faults (issues 18, 31): rows kept after N TCP gaps, foreign exceptions in the fuzz,
and hostile captures (holes, floods, endless streams, many connections) in linear time and bounded memory.

    python benchmarks/faults_capture.py [--cases 2500] [--scale 1.0] [--json]

Rows kept: RTDE sessions written with dpkt, segments left out as a capture tool drops
them; "expected" is every package that shares no byte with a lost segment.
Fuzz: the Hypothesis strategies of tests/faults/test_capture_foreign.py (pcap/pcapng
structure, TCP segments, packages) for CASES cases; a foreign exception is any that is
not an `RtdeSpecError`, or an output that does not read back.
`rows_kept()` and `foreign_exceptions()` are what benchmarks/faults.py can import.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))
sys.path.append(str(ROOT / "benchmarks"))

from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS  # noqa: E402

from tests.capture_files import (  # noqa: E402
    FILE_OPS,
    FRAME_OPS,
    SMALL,
    decode_mutated,
    packages_touched,
    rtde_capture,
    rtde_packages,
)

UR_RTDE = tuple(UR_RTDE_DEFAULT_OUTPUTS)  # 58 fields, 1,180-byte packages
CASES = [  # (label, packages, lost segments as fractions of the stream, segment bytes or None, recipe)
    ("2 gaps, 1 package per segment", 5000, (0.2, 0.9186), None, SMALL),
    ("4 gaps, 1 package per segment", 3000, (0.13, 0.37, 0.37 + 1 / 3000, 0.999), None, SMALL),
    ("4 gaps, 700-byte segments, 64-byte packages", 3000, (0.2, 0.4, 0.6, 0.8), 700, SMALL),
    (
        "4 gaps, 700-byte segments, 1180-byte packages",
        3000,
        (0.2, 0.4, 0.6, 0.8),
        700,
        UR_RTDE_DEFAULT_OUTPUTS,
    ),
    ("20 gaps, 1 package per segment", 3000, tuple(k / 20 + 0.01 for k in range(20)), None, SMALL),
]


def rows_kept() -> list[dict[str, Any]]:
    """Per case: packages, decodable (not touched by a gap), kept, gaps counted."""
    from rtde_spec.capture.decoder import decode_to_directory

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for n, (label, count, where, segment, names) in enumerate(CASES):
            names = tuple(names)
            packages = rtde_packages(count, names)
            pieces = count if segment is None else -(-len(b"".join(packages)) // segment)
            lost = {int(f * pieces) for f in where}
            path = rtde_capture(Path(tmp) / f"c{n}.pcap", packages, lost=lost, segment=segment, names=names)
            decodable = count - (
                len(lost) if segment is None else len(packages_touched(packages, segment, lost))
            )
            summary = decode_to_directory(path, Path(tmp) / f"out{n}")
            kept = summary.tables.get("rtde_outputs_1", 0)
            gaps = sum(c.gaps for c in summary.connections)
            out.append({"case": label, "packages": count, "decodable": decodable, "kept": kept, "gaps": gaps})
    return out


def foreign_exceptions(cases: int = 2500) -> dict[str, Any]:
    """Run the capture fuzz for `cases` cases; count the foreign exceptions and show the first."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    found: list[str] = []
    ran = [0]
    with tempfile.TemporaryDirectory() as tmp:

        @settings(max_examples=cases, deadline=None, database=None, suppress_health_check=list(HealthCheck))
        @given(
            kind=st.sampled_from(["pcap", "pcapng"]),
            sink=st.sampled_from(["parquet", "jsonl", "csv", "arrow"]),
            frame_ops=st.lists(FRAME_OPS, max_size=6),
            file_ops=st.lists(FILE_OPS, max_size=4),
        )
        def one(kind: str, sink: str, frame_ops: list, file_ops: list) -> None:  # type: ignore[type-arg]
            folder = Path(tempfile.mkdtemp(dir=tmp))
            ran[0] += 1
            foreign = decode_mutated(folder, kind, sink, frame_ops, file_ops)
            if foreign is not None:
                found.append(foreign)

        one()
    last_lines = [f.strip().splitlines()[-1] for f in found]
    return {"cases": ran[0], "foreign": len(found), "kinds": sorted(set(last_lines)), "first": found[:1]}


_MEASURE = """
import json, resource, sys, time
from rtde_spec.cli.main import main
start = time.perf_counter()
code = main(["capture", sys.argv[1], "-o", sys.argv[2]])
print(json.dumps({"code": code, "seconds": time.perf_counter() - start,
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def _capture_run(path: Path, out: Path) -> dict[str, Any]:
    """`rtde-spec capture` of one file in its own process: exit code, seconds, peak RSS."""
    import subprocess

    done = subprocess.run(
        [sys.executable, "-c", _MEASURE, str(path), str(out)], capture_output=True, text=True, timeout=3600
    )
    figures: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return figures


HOSTILE = [  # (label, writer, full size; half size runs too, to show time grows linearly)
    ("1-byte segments, each after a 1-byte hole", "holes", 80_000),
    ("50002 stream of newlines (bytes)", "newlines", 30_000_000),
    ("50002 stream without a newline (bytes)", "no_newline", 30_000_000),
    ("SYNs to ports nobody decodes", "syns", 1_500_000),
    ("RTDE connections one after another", "connections", 50_000),
    ("30004 mid-stream, 1-byte segments, no package", "rtde_bytes", 400_000),
    ("30003 1-byte segments, no known size", "realtime_bytes", 400_000),
    ("50003 mid-stream, 1-byte segments, no record", "trajectory_bytes", 400_000),
]


def hostile_figures(scale: float = 1.0, only: str = "") -> list[dict[str, Any]]:
    """Per hostile capture (those whose kind contains `only`): half and full size, seconds and
    peak RSS each, and the time ratio."""
    import hostile_captures as hc

    writers = {
        "holes": hc.holes,
        "newlines": lambda path, n: hc.script_stream(path, n, newlines=True),
        "no_newline": lambda path, n: hc.script_stream(path, n, newlines=False),
        "syns": hc.syn_flood,
        "connections": hc.rtde_connections,
        "rtde_bytes": lambda path, n: hc.byte_by_byte(path, n, 30004),
        "realtime_bytes": lambda path, n: hc.byte_by_byte(path, n, 30003),
        "trajectory_bytes": lambda path, n: hc.byte_by_byte(path, n, 50003),
    }
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, kind, full in HOSTILE:
            if only not in kind:
                continue
            runs = []
            for size in (int(full * scale) // 2, int(full * scale)):
                path = writers[kind](Path(tmp) / f"{kind}-{size}.pcap", size)
                runs.append({"size": size, **_capture_run(path, Path(tmp) / f"out-{kind}-{size}")})
                path.unlink()
            half, whole = runs
            ratio = whole["seconds"] / max(half["seconds"], 1e-9)
            rows.append({"case": label, "half": half, "full": whole, "time_ratio": ratio})
    return rows


def print_hostile(rows: list[dict[str, Any]]) -> None:
    print("hostile captures (half size, full size: seconds, peak RSS, exit code; time ratio ~2 is linear):")
    for row in rows:
        half, full = row["half"], row["full"]
        print(
            f"  {row['case']:44s} {half['size']:>11,}: {half['seconds']:6.1f} s {half['peak_mb']:4.0f} MB  "
            f"{full['size']:>11,}: {full['seconds']:6.1f} s {full['peak_mb']:4.0f} MB exit {full['code']}  "
            f"x{row['time_ratio']:.2f}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=2500, help="fuzz cases (default: 2500)")
    parser.add_argument("--json", action="store_true", help="print one JSON object (default: text)")
    parser.add_argument("--scale", type=float, default=1.0, help="size of the hostile captures (1.0: full)")
    parser.add_argument("--only", default="", help="hostile captures whose kind contains this, alone")
    args = parser.parse_args(argv)
    if args.only:
        print_hostile(hostile_figures(args.scale, args.only))
        return 0
    kept = rows_kept()
    fuzz = foreign_exceptions(args.cases)
    hostile = hostile_figures(args.scale)
    if args.json:
        fuzzed = {k: v for k, v in fuzz.items() if k != "first"}
        print(json.dumps({"rows_kept": kept, "fuzz": fuzzed, "hostile": hostile}))
        return 0
    print_hostile(hostile)
    print("rows kept after TCP gaps (capture, RTDE):")
    for row in kept:
        print(
            f"  {row['case']:48s} {row['kept']:>6,} of {row['decodable']:,} decodable "
            f"({row['packages']:,} sent), {row['gaps']} gaps counted"
        )
    print(f"capture fuzz: {fuzz['foreign']} foreign exceptions in {fuzz['cases']:,} cases")
    for kind in fuzz["kinds"]:
        print(f"  {kind}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
