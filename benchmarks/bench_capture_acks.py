"""A capture as either host takes it (the client's ACK after every data package) against the
same packages captured without ACKs: `capture --jobs 1` as whole processes, in turn round by
round, packages per CPU-second and the ratio (1.0: the ACKs cost nothing).

Every capture the benchmarks made had no ACK frames; before the reader went on over them a real
capture was 8-10x slower than these (commit b710738).

`--piped`: both captures also piped in (`cat FILE | capture -`, as `tcpdump -w - |` gives them),
against the file; the CPU is the capture process's. A pipe holds 64 kB unless widened: read 64 kB
at a time, a piped capture took 5-7x the CPU of the file (~90 packages a block, each costing a
block's set-up), until `capture/reading/pipes.py`.

    python benchmarks/bench_capture_acks.py [--packages 200000] [--rounds 5] [--piped]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent.parent), str(Path(__file__).resolve().parent)]

from bench_capture import Way, print_rates, rates_in_turn  # noqa: E402
from bytecode import keep_bytecode  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packages", type=int, default=200_000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--piped", action="store_true", help="each capture piped in too, against the file")
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
        cli = [sys.executable, "-m", "rtde_spec", "capture"]
        ways: dict[str, Way] = {
            label: ([*cli, str(path), "-o"], args.packages, None) for label, path in files.items()
        }
        plain, acked = files
        pairs = [(plain, acked)]
        if args.piped:
            for label, path in files.items():
                ways[f"{label}, piped"] = ([*cli, "-", "-o"], args.packages, path)
                pairs.append((label, f"{label}, piped"))
        rates = rates_in_turn(ways, args.rounds, work / "out")
        print(f"{args.packages:,} packages of the 58-field recipe, capture (--jobs 1), per CPU-second:")
        print_rates(rates, pairs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
