"""encode_package against a UR-client-style pack, side by side in one run.

Two recipes: an 8-field input recipe (6 doubles + 2 UINT8) as an application sends
it, and ur_rtde's default 58-field output recipe (what our controller emulator
encodes at 500 Hz). The baseline is UR's serialize module's way (DataObject.pack,
then one struct.pack, then the header); ours checks every value's range and type.

    python benchmarks/bench_recipe_encode.py [--calls 20000] [--assert-targets]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_recipe_decode import UR_RTDE_DEFAULT_OUTPUTS
from ur_client_style import DataObject, baseline_encoder, per_call_ns

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


def compare(label: str, names: list[str], direction: str, calls: int) -> float:
    cat = Catalogue.builtin()
    codec = RecipeCodec.for_names(names, direction, cat)  # type: ignore[arg-type]
    types = [cat.get(n, direction).type for n in names]  # type: ignore[arg-type, union-attr]
    values = sample(codec)
    obj = DataObject()
    obj.recipe_id = 1
    for name, value in values.items():
        setattr(obj, name, value)
    send = baseline_encoder(names, types)
    assert send(obj) == codec.encode_package(values, recipe_id=1)
    base = per_call_ns(lambda: send(obj), calls)
    ours = per_call_ns(lambda: codec.encode_package(values, recipe_id=1), calls)
    ratio = base / ours
    print(f"{label:40s} {base / 1000:10.2f} {ours / 1000:10.2f} {ratio:9.2f}x")
    return ratio


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20_000, help="calls per sample (default: 20000)")
    parser.add_argument("--assert-targets", action="store_true", help="exit 1 on a missed target")
    args = parser.parse_args(argv)
    print(f"{'encode_package':40s} {'UR µs':>10s} {'ours µs':>10s} {'speed-up':>10s}")
    ratios = [
        compare("8-field input recipe", INPUTS_8, "input", args.calls),
        compare("58-field output recipe (ur_rtde)", UR_RTDE_DEFAULT_OUTPUTS, "output", args.calls // 4),
    ]
    ok = all(r >= TARGET_RATIO for r in ratios)
    verdict = "met" if ok else "MISSED"
    print(f"\ntarget: >= {TARGET_RATIO}x the UR-client-style pack, range checks included: {verdict}")
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
