"""Start-up of each CLI path, as whole processes, against `python -c pass` in the same rounds.

What a user waits for before anything happens: `--help`, a one-package capture to
Parquet (pyarrow, no pandas), `record` reaching the network (a closed port on
loopback: the time to the refused connection is the time to the first SYN), and
`fields`. Rows are sampled in turn, round by round, so the machine's drift shifts
them alike; the figure is the median over rounds of (command - `python -c pass`).

    python3 benchmarks/startup.py [--rounds 15] [--assert-targets]
"""

from __future__ import annotations

import argparse
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

# target: milliseconds over `python -c pass` (issue "Second first contact", point 5)
TARGETS = {"--help": 70.0, "capture 1 package -> parquet": 300.0, "record -> network": 250.0}


def one_package_pcap(folder: Path) -> Path:
    """An RTDE session's setup and one data package, written with dpkt (the tests' writer)."""
    from rtde_spec import RecipeCodec, build
    from tests.capture_files import Conversation, write

    names = ["timestamp", "actual_q", "robot_mode"]
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("request_protocol_version", protocol_version=2))
    conv.send("server", build("request_protocol_version_reply", accepted=True))
    conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=names))
    types = ["DOUBLE", "VECTOR6D", "INT32"]
    conv.send("server", build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))
    codec = RecipeCodec.for_names(names, "output")
    conv.send("server", codec.encode_package({"timestamp": 1.0, "actual_q": (0.0,) * 6, "robot_mode": 7}, 1))
    return write(folder / "one.pcap", [conv])


RECORD_ARGS = ["--fields", "timestamp", "--timeout", "2", "-o"]


def closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def timed(argv: list[str], cwd: Path, ok: tuple[int, ...]) -> float:
    start = time.perf_counter()
    proc = subprocess.run(argv, cwd=cwd, capture_output=True)
    elapsed = (time.perf_counter() - start) * 1000
    if proc.returncode not in ok:
        raise SystemExit(f"{argv}: exit {proc.returncode}: {proc.stderr.decode(errors='replace')[-400:]}")
    return elapsed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15, help="rounds, each command once per round (15)")
    parser.add_argument("--assert-targets", action="store_true", help="exit 1 when a target is missed")
    args = parser.parse_args()
    py = sys.executable
    cli = [py, "-m", "rtde_spec"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        pcap = one_package_pcap(folder)
        port = str(closed_port())
        rows: dict[str, tuple[list[str], tuple[int, ...]]] = {
            "python -c pass": ([py, "-c", "pass"], (0,)),
            "--help": ([*cli, "--help"], (0,)),
            "fields --controller 5.15": ([*cli, "fields", "--controller", "5.15.0"], (0,)),
            "capture 1 package -> parquet": ([*cli, "capture", str(pcap), "-o", str(folder / "out")], (0,)),
            "record -> network": (
                [*cli, "record", "--host", "127.0.0.1", "--port", port, *RECORD_ARGS, str(folder / "r.csv")],
                (1,),
            ),
        }
        samples: dict[str, list[float]] = {name: [] for name in rows}
        for argv, ok in rows.values():  # one warming run each (page cache, .pyc)
            timed(argv, folder, ok)
        for _ in range(args.rounds):
            for name, (argv, ok) in rows.items():
                samples[name].append(timed(argv, folder, ok))
    base = samples.pop("python -c pass")
    print(f"{'command':32} {'median ms':>10} {'over python':>12} {'target over':>12}")
    print(f"{'python -c pass':32} {statistics.median(base):10.1f}")
    missed = 0
    for name, values in samples.items():
        over = statistics.median(v - b for v, b in zip(values, base, strict=True))
        target = TARGETS.get(name)
        mark = ""
        if target is not None:
            mark = f"{target:9.0f} {'met' if over <= target else 'MISSED'}"
            missed += over > target
        print(f"{name:32} {statistics.median(values):10.1f} {over:12.1f} {mark:>12}")
    return 1 if (missed and args.assert_targets) else 0


if __name__ == "__main__":
    sys.exit(main())
