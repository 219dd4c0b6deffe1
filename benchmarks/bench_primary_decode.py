"""Decode of a UR5e-like Robot State message (13 sub-packages, ~1.4 kB).

Side by side: a plain `struct` baseline (walk the sub-package headers, unpack
each known sub-package with a precompiled struct into a tuple — no names, no
models, no checks) against rtde_spec's decoder (named, typed pydantic models,
compatibility rule, checks). Target: median <= 200 µs on the 2-core machine.

    python benchmarks/bench_primary_decode.py [--assert-targets]
"""

from __future__ import annotations

import argparse
import statistics
import struct
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from ur5e_robot_state import ur5e_robot_state, ur5e_robot_state_bytes

from rtde_spec.primary.codec import decode_message

TARGET_MEDIAN_US = 200.0


def baseline_decoder(data: bytes) -> object:
    """Struct formats per sub-package type, taken from the decoded message itself."""
    from rtde_spec.primary.codec import default_codec

    codec = default_codec()
    family = codec.families[16]
    formats = {}
    for sub_type, (_, layout) in family.members.items():
        if layout.fixed_size is not None:
            formats[sub_type] = struct.Struct(">" + "".join(s.struct.format[1:] for s in layout.steps))  # type: ignore[union-attr]
    header = struct.Struct(">IB")

    def decode(buf: bytes) -> list[tuple]:
        size, _ = header.unpack_from(buf)
        pos = 5
        out = []
        while pos < size:
            sub_size, sub_type = header.unpack_from(buf, pos)
            fmt = formats.get(sub_type)
            if fmt is not None and sub_size - 5 >= fmt.size:
                out.append(fmt.unpack_from(buf, pos + 5))
            else:
                out.append((buf[pos + 5 : pos + sub_size],))
            pos += sub_size
        return out

    return decode


def sample_us(fn, arg, calls: int, repeats: int = 15) -> list[float]:
    samples = []
    for _ in range(repeats):
        start = time.perf_counter_ns()
        for _ in range(calls):
            fn(arg)
        samples.append((time.perf_counter_ns() - start) / calls / 1000)
    return samples


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--assert-targets", action="store_true")
    args = parser.parse_args(argv)
    data = ur5e_robot_state_bytes()
    message = decode_message(data)
    assert message == ur5e_robot_state()
    baseline = baseline_decoder(data)
    assert len(baseline(data)) == len(message.sub_packages) == 13  # type: ignore[union-attr,operator]
    base = sample_us(baseline, data, args.calls)
    ours = sample_us(decode_message, data, args.calls // 4)
    b, o = statistics.median(base), statistics.median(ours)
    print(f"Robot State: {len(data)} bytes, {len(message.sub_packages)} sub-packages\n")  # type: ignore[union-attr]
    print(f"{'decoder':55s} {'median µs':>10s} {'p90 µs':>8s}")
    print(f"{'baseline: struct per sub-package, tuples, no checks':55s} {b:10.1f} {sorted(base)[13]:8.1f}")
    print(f"{'rtde_spec: decode_message (named, typed, checked)':55s} {o:10.1f} {sorted(ours)[13]:8.1f}")
    print(
        f"\nrtde_spec / baseline = {o / b:.1f}x the time; target median <= {TARGET_MEDIAN_US:.0f} µs: "
        f"{'met' if o <= TARGET_MEDIAN_US else 'MISSED'}"
    )
    return 0 if o <= TARGET_MEDIAN_US or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
