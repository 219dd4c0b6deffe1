"""Per-packet and bulk decode of ur_rtde's default 58-field output recipe.

Side by side in one run: a baseline written the way UR's official Python client
decodes (one struct.unpack_from for the recipe, then a dict of fields with
per-type conversion and vectors as lists), against this package's compiled
recipe codec. Prints absolute figures and ratios; exits 1 if a target is missed
when run with --assert-targets.

    python benchmarks/bench_recipe_decode.py [--packets 200000] [--assert-targets]
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ur_client_style import baseline_decoder, per_call_ns

from rtde_spec import Catalogue, RecipeCodec

# ur_rtde 1.6.5 RTDEReceiveInterface(host, 500.0) on a 5.15 controller (observed on the
# wire; shared/reference/ur_rtde-default-outputs.txt)
UR_RTDE_DEFAULT_OUTPUTS = """
timestamp target_q target_qd target_qdd target_current target_moment actual_q actual_qd
actual_current joint_control_output actual_TCP_pose actual_TCP_speed actual_TCP_force
target_TCP_pose target_TCP_speed actual_digital_input_bits joint_temperatures
actual_execution_time robot_mode joint_mode safety_mode actual_tool_accelerometer
speed_scaling target_speed_fraction actual_momentum actual_main_voltage actual_robot_voltage
actual_robot_current actual_joint_voltage actual_digital_output_bits runtime_state
standard_analog_input0 standard_analog_input1 standard_analog_output0 standard_analog_output1
robot_status_bits safety_status_bits ft_raw_wrench payload payload_cog payload_inertia
output_int_register_2 output_int_register_12 output_int_register_13 output_int_register_14
output_int_register_15 output_int_register_16 output_int_register_17 output_int_register_18
output_int_register_19 output_double_register_12 output_double_register_13
output_double_register_14 output_double_register_15 output_double_register_16
output_double_register_17 output_double_register_18 output_double_register_19
""".split()

TARGET_PER_PACKET_RATIO = 10.0  # decode_record against the UR-client-style unpack
TARGET_BULK_PER_SECOND = 1_000_000


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--packets", type=int, default=200_000, help="packages for bulk decode")
    parser.add_argument("--calls", type=int, default=20_000, help="calls per per-packet sample")
    parser.add_argument("--assert-targets", action="store_true")
    args = parser.parse_args(argv)

    cat = Catalogue.builtin()
    names = UR_RTDE_DEFAULT_OUTPUTS
    assert len(names) == 58, len(names)
    codec = RecipeCodec.for_names(names, "output", cat)
    types = [cat.get(n, "output").type for n in names]  # type: ignore[union-attr]
    rng = random.Random(1)
    values = {}
    for item in codec.items:
        one = (lambda: rng.random()) if item.wire.kind == "float" else (lambda: rng.randint(0, 100))
        if item.wire.kind == "bool":
            one = lambda: True  # noqa: E731
        values[item.name] = one() if item.wire.count == 1 else tuple(one() for _ in range(item.wire.count))
    payload = codec.encode(values)
    baseline = baseline_decoder(names, types)
    assert baseline(payload)["actual_q"] == list(codec.decode_record(payload).actual_q)

    floor = codec.struct.unpack_from  # the floor: one precompiled unpack to a flat tuple, nothing else
    # the baseline, the floor and decode_record in turn, round by round: their ratios are
    # the medians of the rounds' ratios (a load change on a shared machine hits all three)
    trio: list[list[float]] = [[], [], []]
    for _ in range(9):
        for out, fn in zip(
            trio,
            (lambda: baseline(payload), lambda: floor(payload), lambda: codec.decode_record(payload)),
            strict=True,
        ):
            out.append(per_call_ns(fn, args.calls // 4, repeats=1))
    base_ns, floor_ns = statistics.median(trio[0]), statistics.median(trio[1])
    rows = [
        ("baseline: UR client style (dict, lists)", base_ns),
        ("floor: struct unpack_from, a flat tuple", floor_ns),
    ]
    rows.append(("record: flat typed record (decode_record)", statistics.median(trio[2])))
    record_vs_base = statistics.median(b / r for b, r in zip(trio[0], trio[2], strict=True))
    record_to_floor = statistics.median(r / f for r, f in zip(trio[2], trio[1], strict=True))
    rows.append(("dict: decode", per_call_ns(lambda: codec.decode(payload), args.calls)))
    model = codec.model_type
    rows.append(
        (
            "pydantic: model_validate (decode_model)",
            per_call_ns(lambda: codec.decode_model(payload), args.calls // 4),
        )
    )
    rows.append(
        (
            "pydantic: model_construct",
            per_call_ns(lambda: model.model_construct(**codec.decode(payload)), args.calls // 4),
        )
    )

    print(f"Recipe: {len(names)} fields, {codec.size} payload bytes, {codec.package_size} per package\n")
    print(f"{'per-packet decode':45s} {'µs/packet':>10s} {'vs baseline':>12s} {'/ floor':>8s}")
    for label, ns in rows:
        print(f"{label:45s} {ns / 1000:10.2f} {base_ns / ns:11.2f}x {ns / floor_ns:7.2f}x")
    print(
        f"(decode_record, medians of the rounds' ratios: {record_vs_base:.2f}x the baseline, "
        f"{record_to_floor:.2f}x the floor's time)"
    )

    package = codec.encode_package(values, recipe_id=1)
    buffer = package * args.packets
    bulk = []
    for _ in range(5):
        start = time.perf_counter()
        arr = codec.decode_many(buffer, recipe_id=1)
        native = arr["actual_q"].astype("=f8")  # touch the data: a real consumer converts
        bulk.append(time.perf_counter() - start)
    bulk_rate = args.packets / statistics.median(bulk)
    assert native.shape == (args.packets, 6)
    loop_packets = min(args.packets, 50_000)
    start = time.perf_counter()
    for i in range(loop_packets):
        baseline(buffer[i * len(package) + 4 : (i + 1) * len(package)])
    loop_rate = loop_packets / (time.perf_counter() - start)
    print(f"\n{'bulk decode':45s} {'packages/s':>12s} {'vs baseline':>12s}")
    print(f"{'baseline loop (UR client style)':45s} {loop_rate:12,.0f} {1:11.2f}x")
    print(
        f"{'decode_many (numpy, checked, zero-copy)':45s} {bulk_rate:12,.0f} {bulk_rate / loop_rate:11.2f}x"
    )

    record_ratio = record_vs_base
    ok = record_ratio >= TARGET_PER_PACKET_RATIO and bulk_rate >= TARGET_BULK_PER_SECOND
    print(
        f"\ntargets: typed per-packet >= {TARGET_PER_PACKET_RATIO}x baseline "
        f"(got {record_ratio:.2f}x), bulk >= {TARGET_BULK_PER_SECOND:,}/s (got {bulk_rate:,.0f}/s): "
        f"{'met' if ok else 'MISSED'}"
    )
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
