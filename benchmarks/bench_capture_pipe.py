"""A capture piped in (`tcpdump -w - | rtde-spec capture -`, `zcat x.pcap.gz | ...`) against the
same file read directly: `capture --jobs 1` as whole processes, in turn round by round, packages
per CPU-second of the capture process (not the writer's) and the ratio (1.0: the pipe costs nothing).

A pipe holds 64 kB unless widened: read 64 kB at a time, a piped capture took 5-7x the CPU of
the file (~90 packages a block, each costing a block's set-up), until `capture/reading/pipes.py`.

    python benchmarks/bench_capture_pipe.py [--packages 200000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent.parent), str(Path(__file__).resolve().parent)]

from bench_capture import cli_usage, make_captures  # noqa: E402
from bytecode import keep_bytecode  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packages", type=int, default=200_000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        keep_bytecode(work)
        plain, acked = work / "plain.pcap", work / "acked.pcap"
        make_captures((plain, args.packages, "10.0.0.10"))
        make_captures((acked, args.packages, "10.0.0.10"), acks=True)
        cli = [sys.executable, "-m", "rtde_spec", "capture"]
        ways = {  # label -> (argv, the file piped in)
            "the file": ([*cli, str(plain), "-o"], None),
            "piped (cat FILE | capture -)": ([*cli, "-", "-o"], plain),
            "with ACKs, the file": ([*cli, str(acked), "-o"], None),
            "with ACKs, piped": ([*cli, "-", "-o"], acked),
        }
        rates: dict[str, list[float]] = {label: [] for label in ways}
        for attempt in range(args.rounds + 1):  # the first round warms the page cache and is not kept
            for label, (argv_, piped) in ways.items():
                _, cpu, _ = cli_usage([*argv_, str(work / "out")], piped)
                if attempt:
                    rates[label].append(args.packages / cpu)
        print(f"{args.packages:,} packages of the 58-field recipe, capture (--jobs 1), per CPU-second:")
        for label, got in rates.items():
            each = ", ".join(f"{r:,.0f}" for r in got)
            print(f"  {label:30s} {statistics.median(got):10,.0f}  (rounds: {each})")
        labels = list(ways)
        for file, pipe in ((labels[0], labels[1]), (labels[2], labels[3])):
            ratio = statistics.median(p / f for f, p in zip(rates[file], rates[pipe], strict=True))
            print(f"  {pipe} / {file}, round by round: {ratio:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
