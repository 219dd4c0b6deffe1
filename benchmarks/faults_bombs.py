"""Peak resident size of the hostile inputs of issue 18.6, each in its own process.

- matrix bomb: a primary global-variables message of 1,000 MATRIX values, each 5 bytes
  declaring 65,535 rows x 0 columns (was > 2.9 GB);
- many small values: a ~1 MB message of the cheapest elements (a LIST of NONE, one
  byte each), what a legitimate-looking message can cost at most per byte;
- YAML alias bomb: a 359-byte recipe file of nested aliases (was > 60 s, > 2.9 GB);
- 2^31 stdin claim: `rtde-spec decode - --protocol primary` given a header claiming
  2^31 bytes, then 64 MiB, the writer not closing;
- 192 MiB through stdin: 1 MiB primary messages piped to `decode -`.

Each child reports its own VmHWM (peak resident size) and wall time; a child runs
under an address-space limit (--limit-gb) so an old version's blow-up ends as
"MemoryError/limit" instead of swapping. Prints one row per input; --json for
benchmarks/faults.py.

    python benchmarks/faults_bombs.py [--json] [--limit-gb 3]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

HWM = """
import atexit, sys
def _hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            sys.stderr.write("\\nVMHWM_KB %s\\n" % line.split()[1])
atexit.register(_hwm)
"""

DECODE_VALUES = (
    HWM
    + """
import struct
from rtde_spec.errors import DecodeError
from rtde_spec.primary.codec import decode_message
values = bytes.fromhex(sys.stdin.read())
body = struct.pack(">QBH", 0, 1, 0) + values
message = struct.pack(">IB", 5 + len(body), 25) + body
try:
    decode_message(message)
    print("decoded")
except DecodeError as exc:
    print(f"DecodeError: {str(exc)[:90]}")
"""
)

LOAD_RECIPE = (
    HWM
    + """
from rtde_spec.errors import RtdeSpecError
from rtde_spec.recipes.files import load_recipes
try:
    print(f"{len(load_recipes(sys.argv[1])[0].names)} names")
except RtdeSpecError as exc:
    print(f"{type(exc).__name__}: {str(exc).splitlines()[0][-90:]}")
"""
)

CLI = (
    HWM
    + """
from rtde_spec.cli.main import main
sys.exit(main(sys.argv[1:]))
"""
)

ALIAS_BOMB = """\
fields:
  - &a [actual_q,actual_q,actual_q,actual_q,actual_q,actual_q,actual_q,actual_q]
  - &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a]
  - &c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b]
  - &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c]
  - &e [*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]
  - &f [*e,*e,*e,*e,*e,*e,*e,*e,*e,*e]
  - &g [*f,*f,*f,*f,*f,*f,*f,*f,*f,*f]
  - [*g,*g,*g,*g,*g,*g,*g,*g,*g,*g]
"""


def run_child(code: str, args: list[str], stdin: bytes, limit: int, timeout: float) -> dict[str, object]:
    """Run `code` in a child under an address-space limit; its peak RSS, time and outcome."""

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    env = {**os.environ, "PYTHONPATH": os.environ.get("PYTHONPATH", str(ROOT))}
    started = time.monotonic()
    try:
        proc = subprocess.run(
            [sys.executable, "-c", code, *args],
            input=stdin,
            capture_output=True,
            timeout=timeout,
            env=env,
            preexec_fn=cap,
        )
    except subprocess.TimeoutExpired:
        return {"peak_mb": None, "seconds": timeout, "outcome": f"killed after {timeout:.0f} s"}
    seconds = time.monotonic() - started
    err = proc.stderr.decode(errors="replace")
    kb = [int(x.split()[1]) for x in err.splitlines() if x.startswith("VMHWM_KB")]
    lines = [x for x in err.splitlines() if x.strip() and not x.startswith("VMHWM_KB")]
    outcome = proc.stdout.decode(errors="replace").strip().splitlines()[-1:] or lines[-1:] or [""]
    if "MemoryError" in err:
        outcome = ["MemoryError at the address-space limit"]
    return {
        "peak_mb": round(kb[0] / 1024, 1) if kb else None,
        "seconds": round(seconds, 2),
        "exit": proc.returncode,
        "outcome": outcome[0][:110],
    }


def stdin_claim(limit: int, timeout: float) -> dict[str, object]:
    """A header claiming 2^31 bytes, then 64 MiB, stdin left open: how soon and how big."""

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    env = {**os.environ, "PYTHONPATH": os.environ.get("PYTHONPATH", str(ROOT))}
    args = ["decode", "-", "--protocol", "primary", "--format", "jsonl"]
    started = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-c", CLI, *args],
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=env,
        preexec_fn=cap,
    )
    assert proc.stdin is not None and proc.stderr is not None
    try:
        proc.stdin.write(struct.pack(">IB", 1 << 31, 16))
        for _ in range(64):
            proc.stdin.write(bytes(1 << 20))
        proc.stdin.flush()
        code = proc.wait(timeout=timeout)  # stdin still open: a decoder waiting for EOF times out
        outcome = "refused before the end of stdin"
    except BrokenPipeError:
        code = proc.wait(timeout=timeout)
        outcome = "refused before the end of stdin"
    except subprocess.TimeoutExpired:
        proc.stdin.close()  # now the end: what the old code waited for
        code = proc.wait(timeout=600)
        outcome = f"waited for the end of stdin ({timeout:.0f} s)"
    finally:
        if not proc.stdin.closed:
            try:
                proc.stdin.close()
            except BrokenPipeError:
                pass
    err = proc.stderr.read().decode(errors="replace")
    kb = [int(x.split()[1]) for x in err.splitlines() if x.startswith("VMHWM_KB")]
    return {
        "peak_mb": round(kb[0] / 1024, 1) if kb else None,
        "seconds": round(time.monotonic() - started, 2),
        "exit": code,
        "outcome": outcome,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="one JSON object instead of a table")
    parser.add_argument("--limit-gb", type=float, default=3.0, help="address-space limit of each child")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds before a child is killed")
    args = parser.parse_args(argv)
    limit = int(args.limit_gb * (1 << 30))
    matrix = (bytes([18]) + struct.pack(">HH", 65535, 0) + b"\n") * 1000
    nones = (bytes([17]) + struct.pack(">H", 65000) + bytes(65000) + b"\n") * 15
    message = struct.pack(">IB", 1 << 20, 99) + bytes((1 << 20) - 5)
    results: dict[str, dict[str, object]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        bomb = Path(tmp) / "laughs.yaml"
        bomb.write_text(ALIAS_BOMB)
        results["matrix bomb (6 kB)"] = run_child(
            DECODE_VALUES, [], matrix.hex().encode(), limit, args.timeout
        )
        results["1 MB list of NONE"] = run_child(DECODE_VALUES, [], nones.hex().encode(), limit, args.timeout)
        results[f"YAML alias bomb ({len(ALIAS_BOMB)} B)"] = run_child(
            LOAD_RECIPE, [str(bomb)], b"", limit, args.timeout
        )
    results["2^31 stdin claim"] = stdin_claim(limit, min(args.timeout, 30.0))
    results["192 MiB through stdin"] = run_child(
        CLI,
        ["decode", "-", "--protocol", "primary", "--format", "jsonl", "-o", os.devnull],
        message * 192,
        limit,
        args.timeout * 3,
    )
    if args.json:
        print(json.dumps(results, indent=2))
        return 0
    print(f"{'input':28s} {'peak RSS MB':>11s} {'seconds':>8s} {'exit':>4s}  outcome")
    for name, r in results.items():
        peak = "-" if r["peak_mb"] is None else f"{r['peak_mb']:.0f}"
        print(f"{name:28s} {peak:>11s} {r['seconds']:>8} {r.get('exit', '-')!s:>4}  {r['outcome']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
