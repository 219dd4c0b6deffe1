"""encode_package against a UR-client-style pack, side by side in one run.

Two recipes: an 8-field input recipe (6 doubles + 2 UINT8) as an application sends
it, and ur_rtde's default 58-field output recipe (what our controller emulator
encodes at 500 Hz). The baseline is UR's serialize module's way (DataObject.pack,
then one struct.pack, then the header). Ours is timed twice: the default mode
(ranges checked, lenient types) and strict=True (exact types as well). The three
are timed in turn, round by round, and each row's speed-up is the median of the
rounds' ratios, so a load change on a shared machine hits all three alike.

    python benchmarks/bench_recipe_encode.py [--calls 20000] [--rounds 9] [--assert-targets]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS
from ur_client_style import DataObject, baseline_encoder

from rtde_spec import Catalogue, RecipeCodec

TARGET_RATIO = 1.5
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


def compare(label: str, names: list[str], direction: str, calls: int, rounds: int) -> list[float]:
    """Print one row per mode; return each mode's speed-up over the baseline."""
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
    assert package == codec.encode_package(values, recipe_id=1)
    assert package == codec.encode_package(values, recipe_id=1, strict=True)
    runs: dict[str, Callable[[], object]] = {
        "UR": lambda: send(obj),
        "default": lambda: codec.encode_package(values, recipe_id=1),
        "strict": lambda: codec.encode_package(values, recipe_id=1, strict=True),
    }
    times: dict[str, list[float]] = {k: [] for k in runs}
    for _ in range(rounds):
        for key, fn in runs.items():
            times[key].append(_mean_ns(fn, calls))
    ratios = []
    base = statistics.median(times["UR"])
    for key in ("default", "strict"):
        ratio = statistics.median(b / o for b, o in zip(times["UR"], times[key], strict=True))
        ours = statistics.median(times[key])
        row = f"{label}, {key}" if key == "default" else f"{label}, strict=True"
        print(f"{row:48s} {base / 1000:10.2f} {ours / 1000:10.2f} {ratio:9.2f}x")
        ratios.append(ratio)
    return ratios


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20_000, help="calls per sample (default: 20000)")
    parser.add_argument("--rounds", type=int, default=9, help="rounds of the three in turn (default: 9)")
    parser.add_argument("--assert-targets", action="store_true", help="exit 1 on a missed target")
    args = parser.parse_args(argv)
    print(f"{'encode_package':48s} {'UR µs':>10s} {'ours µs':>10s} {'speed-up':>10s}")
    ratios = [
        *compare("8-field input recipe", INPUTS_8, "input", args.calls, args.rounds),
        *compare(
            "58-field output recipe (ur_rtde)",
            UR_RTDE_DEFAULT_OUTPUTS,
            "output",
            args.calls // 4,
            args.rounds,
        ),
    ]
    ok = all(r >= TARGET_RATIO for r in ratios)
    verdict = "met" if ok else "MISSED"
    print(f"\ntarget: >= {TARGET_RATIO}x the UR-client-style pack, both modes, ranges checked: {verdict}")
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
