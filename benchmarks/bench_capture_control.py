"""A control session's capture (ur_rtde's control interface, URCL's RTDE writer: an input package
after every output, both sides' ACKs) against the same outputs without the inputs, and two such
sessions interleaved package by package: `capture --jobs 1` as whole processes, in turn round by
round, packages per CPU-second (every package counted) and the ratio to the outputs alone.

Until runs went on over the other direction's packages and other connections' segments
(`capture/reading/bulk.py`), such captures were read frame by frame: 5x the CPU per package.

    python benchmarks/bench_capture_control.py [--packages 100000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

from bench_capture import Way, print_rates, rates_in_turn  # noqa: E402
from bytecode import keep_bytecode  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packages", type=int, default=100_000, help="outputs per session (default 100,000)")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args(argv)
    n = args.packages
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        keep_bytecode(work)
        kinds = {  # label -> (keyword arguments of control_capture, packages in the file)
            "outputs alone (ACKs)": ("inputs=False", n),
            "control session (inputs, ACKs)": ("inputs=True", 2 * n),
            "two control sessions interleaved": ("inputs=True, clients=2", 4 * n // 2),
        }
        code = "import sys; sys.path[:0] = sys.argv[1:2]\nfrom pathlib import Path\n"
        code += "from tests.capture_files import control_capture\n"
        for i, (kw, _) in enumerate(kinds.values()):
            count = n // 2 if "clients=2" in kw else n
            code += f"control_capture(Path({str(work / f'{i}.pcap')!r}), acks=True, count={count}, {kw})\n"
        subprocess.run([sys.executable, "-c", code, str(ROOT)], check=True)
        cli = [sys.executable, "-m", "rtde_spec", "capture"]
        ways: dict[str, Way] = {
            label: ([*cli, str(work / f"{i}.pcap"), "-o"], packages, None)
            for i, (label, (_, packages)) in enumerate(kinds.items())
        }
        rates = rates_in_turn(ways, args.rounds, work / "out")
        print(f"{n:,} outputs of a 3-field recipe a session, capture (--jobs 1), packages per CPU-second:")
        alone, *others = kinds
        print_rates(rates, [(alone, label) for label in others])
    return 0


if __name__ == "__main__":
    sys.exit(main())
