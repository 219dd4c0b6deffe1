"""Instructions per call of the issue-30 rows under callgrind: figures the machine's load does not change.

Each row runs in its own `valgrind --tool=callgrind` process twice, with N calls and with
none after the same setup and warm-up; the difference over N is the row's instructions
per call. Rows: decode of a 58-field data package, encode of 8 and 58 fields (default and
strict), a URSim 5.8 Robot State (`rs`: one message repeated; `rsmove`: the next message
of a stream of distinct ones as a moving robot sends them, see
`ur5e_robot_state.moving_robot_stream`), each beside its floor and its peer; `values12` and
`objects12` are the bounds of `bench_primary_decode.bound_decoder` (our decoder minus its
models: values in tuples; model objects holding no values).

    python benchmarks/instructions.py [--calls 1000] [ROW ...]     (needs valgrind)
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
BOUNDS = ("values12", "objects12")  # our Robot State decoder minus its models (bench_primary_decode)
ROWS = [
    *(f"dec:{m}" for m in ("floor", "record", "UR")),
    *(f"enc8:{m}" for m in ("floor", "default", "strict", "UR")),
    *(f"enc58:{m}" for m in ("floor", "default", "strict", "UR")),
    *(f"rs:{m}" for m in ("floor", "ours", "stream", "floor12", "ours12", "urx")),
    *(f"rsmove:{m}" for m in ("floor", "ours", "stream", "floor12", "ours12", "urx", *BOUNDS)),
]
STREAM_FILE = "RTDE_SPEC_BENCH_STREAM"  # environment: the file holding the moving-robot stream


def _encode(names: list[str], direction: str, mode: str) -> Callable[[], object]:
    from bench_recipe_encode import sample, struct_floor
    from ur_client_style import DataObject, baseline_encoder

    from rtde_spec import Catalogue, RecipeCodec

    cat = Catalogue.builtin()
    codec = RecipeCodec.for_names(names, direction, cat)  # type: ignore[arg-type]
    values = sample(codec)
    if mode == "floor":
        floor = struct_floor(codec)
        return lambda: floor(values)
    if mode == "UR":
        obj = DataObject()
        obj.recipe_id = 1
        for key, value in values.items():
            setattr(obj, key, value)
        send = baseline_encoder(names, [cat.get(n, direction).type for n in names])  # type: ignore[arg-type, union-attr]
        return lambda: send(obj)
    strict = mode == "strict"
    return lambda: codec.encode_package(values, 1, strict)


def _robot_state(mode: str, moving: bool) -> Callable[[], object]:
    """One message a call: the benchmark's message repeated, or (moving) the next of the
    moving-robot stream (`ur5e_robot_state.moving_robot_stream`, round and round)."""
    import itertools
    import os

    import bench_primary_decode as bench
    from ur5e_robot_state import ur5e_robot_state_bytes

    from rtde_spec import decode_message
    from rtde_spec.primary.codec import PrimaryStreamDecoder

    data = ur5e_robot_state_bytes()
    if moving:  # written by the parent process: building it under callgrind would take minutes
        blob = Path(os.environ[STREAM_FILE]).read_bytes()
        messages, pos = [], 0
        while pos < len(blob):
            size = int.from_bytes(blob[pos : pos + 4], "big")
            messages.append(blob[pos : pos + size])
            pos += size
    else:
        messages = [data]
    if mode.endswith("12") or mode == "urx":  # the 12 sub-packages urx reads
        messages = [bench.without_last_sub_package(m) for m in messages]
    it = itertools.cycle(messages)
    if mode.startswith("floor"):
        floor = bench.baseline_decoder(data)
        return lambda: floor(next(it))
    if mode in ("values12", "objects12"):  # the bounds: our generated code minus its models
        bound = bench.bound_decoder(mode[:-2], messages[:2])
        return lambda: bound(next(it))
    if mode == "stream":
        stream = PrimaryStreamDecoder()
        return lambda: stream.feed(next(it))
    if mode == "urx":
        import logging

        from urx.ursecmon import ParserUtils

        logging.disable(logging.CRITICAL)
        return lambda: ParserUtils().parse(next(it))
    return lambda: decode_message(next(it))


def _decode(mode: str) -> Callable[[], object]:
    from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS as names
    from bench_recipe_encode import sample
    from ur_client_style import baseline_decoder

    from rtde_spec import Catalogue, RecipeCodec

    cat = Catalogue.builtin()
    codec = RecipeCodec.for_names(names, "output", cat)
    payload = codec.encode(sample(codec))
    if mode == "floor":
        floor = codec.struct.unpack_from
        return lambda: floor(payload)
    if mode == "UR":
        base = baseline_decoder(names, [cat.get(n, "output").type for n in names])  # type: ignore[union-attr]
        return lambda: base(payload)
    return lambda: codec.decode_record(payload)


def run_row(row: str, calls: int) -> None:
    """In the measured process: set the row up, warm it, then call it `calls` times."""
    sys.path.insert(0, str(HERE))
    kind, mode = row.split(":")
    if kind == "dec":
        fn = _decode(mode)
    elif kind in ("rs", "rsmove"):
        fn = _robot_state(mode, kind == "rsmove")
    else:
        from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS
        from bench_recipe_encode import INPUTS_8

        fn = (
            _encode(INPUTS_8, "input", mode)
            if kind == "enc8"
            else _encode(UR_RTDE_DEFAULT_OUTPUTS, "output", mode)
        )
    for _ in range(50):  # learned shapes, caches of the codecs
        fn()
    for _ in range(calls):
        fn()


def instructions(row: str, calls: int) -> int:
    """Instructions the process ran, under callgrind."""
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"]
    out = subprocess.run(
        [*cmd, sys.executable, __file__, "--run", row, "--calls", str(calls)],
        capture_output=True,
        text=True,
        check=True,
    )
    return int(re.search(r"Collected : (\d+)", out.stderr).group(1))  # type: ignore[union-attr]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows", nargs="*", default=ROWS, help=f"rows (default: all: {' '.join(ROWS)})")
    parser.add_argument("--calls", type=int, default=1000)
    parser.add_argument("--messages", type=int, default=1000, help="distinct messages of the rsmove rows")
    parser.add_argument("--run", help=argparse.SUPPRESS)  # inside the measured process
    args = parser.parse_args(argv)
    if args.run:
        run_row(args.run, args.calls)
        return 0
    if shutil.which("valgrind") is None:
        print("valgrind is not installed")
        return 1
    os.environ.setdefault("PYTHONHASHSEED", "0")  # the same process twice: the same string hashes
    with tempfile.TemporaryDirectory(prefix="rs-stream-") as tmp:
        if any(r.startswith("rsmove:") for r in args.rows):
            sys.path.insert(0, str(HERE))
            from ur5e_robot_state import moving_robot_stream

            path = Path(tmp) / "stream.bin"
            path.write_bytes(b"".join(moving_robot_stream(args.messages)))
            os.environ[STREAM_FILE] = str(path)
        count_rows(args.rows, args.calls)
    return 0


def count_rows(rows: list[str], calls: int) -> None:
    counts = {}
    for row in rows:
        counts[row] = (instructions(row, calls) - instructions(row, 0)) // calls
        kind = row.split(":")[0]
        floor = counts.get(f"{kind}:floor12") if row.endswith("12") else None
        floor = floor or counts.get(f"{kind}:floor")
        to_floor = f"{counts[row] / floor:6.2f}x the floor" if floor else ""
        print(f"{row:14s} {counts[row]:10,d} instructions per call  {to_floor}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
