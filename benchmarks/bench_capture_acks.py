"""A capture as either host takes it (the client's ACK after every data package) against the
same packages captured without ACKs: `capture --jobs 1` as whole processes, in turn round by
round, packages per CPU-second and the ratio (1.0: the ACKs cost nothing).

Every capture the benchmarks made had no ACK frames; before the reader went on over them a real
capture was 8-10x slower than these (commit b710738).

    python benchmarks/bench_capture_acks.py [--packages 200000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent.parent), str(Path(__file__).resolve().parent)]

from bench_capture import cli_usage  # noqa: E402
from bytecode import keep_bytecode  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packages", type=int, default=200_000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    import subprocess

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        keep_bytecode(work)
        files = {"without ACKs": work / "plain.pcap", "an ACK after each package": work / "acked.pcap"}
        code = "import sys; sys.path[:0] = sys.argv[1:3]\nfrom pathlib import Path\n"
        code += "from bench_capture import make_capture\n"
        for path, acks in zip(files.values(), (False, True), strict=True):
            code += f"make_capture(Path({str(path)!r}), {args.packages}, acks={acks})\n"
        here = Path(__file__).resolve().parent
        subprocess.run([sys.executable, "-c", code, str(here.parent), str(here)], check=True)
        rates: dict[str, list[float]] = {label: [] for label in files}
        for attempt in range(args.rounds + 1):  # the first round warms the page cache and is not kept
            for label, path in files.items():
                out = str(work / "out")
                _, cpu, _ = cli_usage([sys.executable, "-m", "rtde_spec", "capture", str(path), "-o", out])
                if attempt:
                    rates[label].append(args.packages / cpu)
        print(f"{args.packages:,} packages of the 58-field recipe, capture (--jobs 1), per CPU-second:")
        for label, got in rates.items():
            each = ", ".join(f"{r:,.0f}" for r in got)
            print(f"  {label:28s} {statistics.median(got):10,.0f}  (rounds: {each})")
        plain, acked = rates.values()
        ratio = statistics.median(b / a for a, b in zip(plain, acked, strict=True))
        print(f"  with ACKs / without, round by round: {ratio:.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
