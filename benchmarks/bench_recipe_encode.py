"""encode_package against a UR-client-style pack, side by side in one run.

Two recipes: an 8-field input recipe (6 doubles + 2 UINT8) as an application sends
it, and ur_rtde's default 58-field output recipe (what our controller emulator
encodes at 500 Hz). The baseline is UR's serialize module's way (DataObject.pack,
then one struct.pack, then the header). Ours is timed twice: the default mode
(ranges checked, lenient types) and strict=True (exact types as well). The three
are timed in turn, round by round, and each row's speed-up is the median of the
rounds' ratios, so a load change on a shared machine hits all three alike.

The floor is the same work with nothing else: the values taken out of the dict in one
`itemgetter` call and one precompiled `struct.pack` of the prefix and the values (no
checks, no dispatch). Targets: >= 1.5x the UR-client-style pack; at most 1.5x the
floor's time (strict: 2x).

    python benchmarks/bench_recipe_encode.py [--calls 20000] [--rounds 9] [--assert-targets]
"""

from __future__ import annotations

import argparse
import statistics
import struct
import sys
import time
from collections.abc import Callable
from operator import itemgetter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS
from ur_client_style import DataObject, baseline_encoder

from rtde_spec import Catalogue, RecipeCodec

TARGET_RATIO = 1.5
TARGET_FLOOR = {"default": 1.5, "strict": 2.0}  # our time / the floor's, at most
INPUTS_8 = [f"input_double_register_{i}" for i in range(24, 30)] + [
    "standard_digital_output_mask",
    "standard_digital_output",
]


def sample(codec: RecipeCodec) -> dict[str, object]:
    values: dict[str, object] = {}
    for i, item in enumerate(codec.items):
        one: object = {"float": 0.25 * i, "int": i % 200, "bool": True}[item.wire.kind]
        values[item.name] = one if item.wire.count == 1 else (one,) * item.wire.count
    return values


def _mean_ns(fn: Callable[[], object], calls: int) -> float:
    start = time.perf_counter_ns()
    for _ in range(calls):
        fn()
    return (time.perf_counter_ns() - start) / calls


def struct_floor(codec: RecipeCodec) -> Callable[[dict[str, object]], bytes]:
    """The values out of the dict in one call, then one pack: what any encoder must do."""
    packer = struct.Struct(">HBB" + codec.struct.format[1:])
    names = [f"x{i}" for i in range(len(codec.items))]
    flat = ", ".join(x if i.wire.count == 1 else f"*{x}" for x, i in zip(names, codec.items, strict=True))
    body = f"{', '.join(names)}, = get(v)\n    return pack({codec.package_size}, 85, 1, {flat})"
    src = f"def floor(v):\n    {body}"
    scope = {"get": itemgetter(*codec.names), "pack": packer.pack}
    exec(src, scope)
    floor: Callable[[dict[str, object]], bytes] = scope["floor"]  # type: ignore[assignment]
    return floor


def compare(label: str, names: list[str], direction: str, calls: int, rounds: int) -> list[bool]:
    """Print one row per mode; return whether each mode met its targets."""
    cat = Catalogue.builtin()
    codec = RecipeCodec.for_names(names, direction, cat)  # type: ignore[arg-type]
    types = [cat.get(n, direction).type for n in names]  # type: ignore[arg-type, union-attr]
    values = sample(codec)
    obj = DataObject()
    obj.recipe_id = 1
    for name, value in values.items():
        setattr(obj, name, value)
    send = baseline_encoder(names, types)
    package = send(obj)
    floor = struct_floor(codec)
    assert package == floor(values) == codec.encode_package(values, recipe_id=1)
    assert package == codec.encode_package(values, recipe_id=1, strict=True)
    runs: dict[str, Callable[[], object]] = {
        "UR": lambda: send(obj),
        "floor": lambda: floor(values),
        "default": lambda: codec.encode_package(values, recipe_id=1),
        "strict": lambda: codec.encode_package(values, recipe_id=1, strict=True),
    }
    times: dict[str, list[float]] = {k: [] for k in runs}
    for _ in range(rounds):
        for key, fn in runs.items():
            times[key].append(_mean_ns(fn, calls))
    met = []
    base, low = statistics.median(times["UR"]), statistics.median(times["floor"])
    for key in ("default", "strict"):
        ratio = statistics.median(b / o for b, o in zip(times["UR"], times[key], strict=True))
        to_floor = statistics.median(o / f for f, o in zip(times["floor"], times[key], strict=True))
        ours = statistics.median(times[key])
        row = f"{label}, {key}" if key == "default" else f"{label}, strict=True"
        us = f"{base / 1000:7.2f} {low / 1000:7.2f} {ours / 1000:7.2f}"
        print(f"{row:44s} {us} {ratio:8.2f}x {to_floor:8.2f}x")
        met.append(ratio >= TARGET_RATIO and to_floor <= TARGET_FLOOR[key])
    return met


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20_000, help="calls per sample (default: 20000)")
    parser.add_argument("--rounds", type=int, default=9, help="rounds of the three in turn (default: 9)")
    parser.add_argument("--assert-targets", action="store_true", help="exit 1 on a missed target")
    args = parser.parse_args(argv)
    head = f"{'encode_package':44s} {'UR µs':>7s} {'floor':>7s} {'ours µs':>7s} {'vs UR':>9s} {'/ floor':>9s}"
    print(head)
    verdicts = [
        *compare("8-field input recipe", INPUTS_8, "input", args.calls, args.rounds),
        *compare(
            "58-field output recipe (ur_rtde)",
            UR_RTDE_DEFAULT_OUTPUTS,
            "output",
            args.calls // 4,
            args.rounds,
        ),
    ]
    ok = all(verdicts)
    verdict = "met" if ok else "MISSED"
    print(
        f"\ntargets: >= {TARGET_RATIO}x the UR-client-style pack, both modes, ranges checked; "
        f"<= {TARGET_FLOOR['default']}x the floor's time (strict <= {TARGET_FLOOR['strict']}x): {verdict}"
    )
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
