"""Decode of a UR5e-like Robot State message (13 sub-packages, ~1.3 kB), beside python-urx.

Side by side in one run: a plain `struct` floor (walk the sub-package headers, unpack
each known sub-package into a tuple: no names, no models, no checks), python-urx's
parser (package `urx` from the registry, `urx.ursecmon.ParserUtils`), and rtde_spec's
decoder (named, typed pydantic models, compatibility rule, checks).

urx takes sub-package type 16 for a message header and re-parses its body, so it
cannot read the UR5e message whole; urx and rtde_spec are compared on the same
message without that last sub-package, a layout both read.

Targets: median <= 50 µs for the 13 sub-packages; >= 4x faster than urx.

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

from ur5e_robot_state import ur5e_robot_state_bytes

from rtde_spec import decode_message

TARGET_MEDIAN_US = 50.0
TARGET_VS_URX = 4.0


def without_last_sub_package(data: bytes) -> bytes:
    """The message minus its last sub-package (cumulative runtime data, type 16)."""
    pos, last = 5, 5
    while pos < len(data):
        last = pos
        pos += struct.unpack_from(">I", data, pos)[0]
    body = data[5:last]
    return struct.pack(">IB", 5 + len(body), 16) + body


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
    baseline = baseline_decoder(data)
    assert len(baseline(data)) == len(message.sub_packages) == 13  # type: ignore[union-attr,operator]
    shared = without_last_sub_package(data)
    rows = [
        (
            "struct floor: tuples, no names, no checks (13 sub-packages)",
            sample_us(baseline, data, args.calls),
        ),
        ("rtde_spec: decode_message (13 sub-packages)", sample_us(decode_message, data, args.calls // 4)),
        (
            "rtde_spec: decode_message (12, the layout urx reads)",
            sample_us(decode_message, shared, args.calls // 4),
        ),
    ]
    try:
        from urx.ursecmon import ParserUtils
    except ImportError:
        print("python-urx is not installed: pip install urx (the benchmark's comparison)")
        urx_median = None
    else:
        parsed = ParserUtils().parse(shared)
        assert parsed["JointData"]["q_actual5"] == message["joint_data"].joints[5].q_actual  # type: ignore[index]
        rows.append(
            (
                "python-urx: ParserUtils().parse (12)",
                sample_us(lambda d: ParserUtils().parse(d), shared, args.calls // 8),
            )
        )
        urx_median = statistics.median(rows[-1][1])
    print(f"Robot State: {len(data)} bytes, {len(message.sub_packages)} sub-packages\n")  # type: ignore[union-attr]
    print(f"{'decoder':62s} {'median µs':>10s} {'p90 µs':>8s}")
    for label, samples in rows:
        print(f"{label:62s} {statistics.median(samples):10.1f} {sorted(samples)[13]:8.1f}")
    ours, ours_shared = statistics.median(rows[1][1]), statistics.median(rows[2][1])
    ok = ours <= TARGET_MEDIAN_US
    print(f"\nrtde_spec median {ours:.1f} µs (target <= {TARGET_MEDIAN_US:.0f})")
    if urx_median is not None:
        ratio = urx_median / ours_shared
        ok = ok and ratio >= TARGET_VS_URX
        target = f"target >= {TARGET_VS_URX:.0f}x"
        print(f"rtde_spec vs python-urx on the same message: {ratio:.1f}x faster ({target})")
    print(f"targets: {'met' if ok else 'MISSED'}")
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
