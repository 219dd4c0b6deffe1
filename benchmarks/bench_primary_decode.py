"""Decode of UR5e-like Robot State messages (13 sub-packages, ~1.3 kB), beside python-urx.

Side by side in one run: a plain `struct` floor (walk the sub-package headers, unpack
each known sub-package into a tuple: no names, no models, no checks), python-urx's
parser (package `urx` from the registry, `urx.ursecmon.ParserUtils`), and rtde_spec's
decoder (named, typed pydantic models, compatibility rule, checks).

The main rows decode a stream of distinct messages as a moving robot sends them
(`ur5e_robot_state.moving_robot_stream`): in every message the robot mode timestamp, the
joints, the pose, the masterboard's and the tool's analog values, voltages, currents and
temperatures, the forces and the energy counters change; kinematics, configuration,
additional info, safety, tool communication and tool mode keep their bytes, as on a real
robot. A controller sends the same sub-package sizes every time, so rtde_spec decodes a
message of a shape seen before with one generated function, which hands out the model of
an unchanged sub-package again (models are frozen). Every row reads the same stream.

The older rows decode one message repeated (every sub-package unchanged, so every one is
reused: the best case, not a robot), and every message as a first sighting (one
generated decoder per sub-package, no reuse).

urx takes sub-package type 16 for a message header and re-parses its body, so it
cannot read the UR5e message whole; urx and rtde_spec are compared on the same
messages without that last sub-package, a layout both read.

Two bound rows take rtde_spec's own generated decoder and remove its models: values in
tuples (the unpacks, checks and reuse), then the model objects allocated but holding no
values. What any decoder returning these models costs at least; the last line compares
the objects alone with the time 12x python-urx leaves.

`PrimaryStreamDecoder` is fed one message a feed (framing included), as a client reading
a 10 Hz stream is. Each row is also given as a ratio to the floor's time on the same
messages, and urx's time to ours, both per round (medians of the rounds' ratios).

Targets (issue 30.1), on the stream, for decode_message and PrimaryStreamDecoder:
<= 2x the floor and >= 12x python-urx.

    python benchmarks/bench_primary_decode.py [--messages 1000] [--rounds 15] [--assert-targets]
"""

from __future__ import annotations

import argparse
import statistics
import struct
import sys
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from ur5e_robot_state import MOVING, moving_robot_stream, ur5e_robot_state_bytes

from rtde_spec import Catalogue, decode_message
from rtde_spec.primary.codec import PrimaryCodec, PrimaryStreamDecoder
from rtde_spec.wire.primary_base import RobotStateMessage

TARGET_TO_FLOOR = 2.0  # issue 30.1, on the stream, through both APIs
TARGET_VS_URX = 12.0
STREAM_ROW = "rtde_spec: PrimaryStreamDecoder.feed, a message a feed (13)"
OBJECTS_ROW = "bound: + the model objects, holding no values (12)"


def without_last_sub_package(data: bytes) -> bytes:
    """The message minus its last sub-package (cumulative runtime data, type 16)."""
    pos, last = 5, 5
    while pos < len(data):
        last = pos
        pos += struct.unpack_from(">I", data, pos)[0]
    body = data[5:last]
    return struct.pack(">IB", 5 + len(body), 16) + body


def baseline_decoder(data: bytes) -> Callable[[bytes], list[tuple[object, ...]]]:
    """Struct formats per sub-package type, taken from the decoded message itself."""
    from rtde_spec.primary.codec import default_codec

    codec = default_codec()
    family = codec.families[16]
    formats = {}
    for sub_type, (_, layout) in family.members.items():
        if layout.fixed_size is not None:
            formats[sub_type] = struct.Struct(">" + "".join(s.struct.format[1:] for s in layout.steps))  # type: ignore[union-attr]
    header = struct.Struct(">IB")

    def decode(buf: bytes) -> list[tuple[object, ...]]:
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


def bound_decoder(kind: str, learn: list[bytes]) -> Callable[[bytes], object]:
    """rtde_spec's own generated shape decoder with its models taken out: what any decoder
    returning these models costs at least. `values`: each model's values in a tuple, no model
    (the unpacks, the header checks and the reuse of unchanged sub-packages); `objects`: each
    model allocated as rtde_spec allocates it, holding no values (the objects alone).
    The difference to `decode_message` is what filling the models' values costs."""
    from rtde_spec.primary import compiled

    def model(src: compiled.Source, cls: type, entries: list[str]) -> str:
        var, name = src.name("m"), src.name("C", cls)
        values = ", ".join(e.split(": ", 1)[1] for e in entries)
        src.add(f"{var} = ({values},)" if kind == "values" else f"{var} = _new({name})")
        return var

    codec = PrimaryCodec(Catalogue.builtin().spec)
    real = compiled.Source.model
    compiled.Source.model = model  # type: ignore[assignment,method-assign]
    try:
        for m in learn * 3:  # a shape is compiled the second time it is seen
            codec.decode_message(m)
    finally:
        compiled.Source.model = real  # type: ignore[method-assign]
    assert codec.robot_state.shapes, "the bound's shape was not compiled"
    return codec.decode_message


Row = tuple[str, Callable[[], object], int, str]  # label, run (all its messages), messages per run, group


def over(fn: Callable[[bytes], object], messages: list[bytes]) -> Callable[[], object]:
    """One run: `fn` on every message in turn."""

    def run() -> None:
        for m in messages:
            fn(m)

    return run


def interleaved_us(rows: list[Row], repeats: int) -> list[list[float]]:
    """µs per message of each row, the rows' repeats taken in turn: the machine's speed
    drifts, and a drift then shifts every row alike instead of one."""
    samples: list[list[float]] = [[] for _ in rows]
    for _ in range(repeats):
        for out, (_, run, count, _) in zip(samples, rows, strict=True):
            start = time.perf_counter_ns()
            run()
            out.append((time.perf_counter_ns() - start) / count / 1000)
    return samples


def urx_parser() -> Callable[[bytes], object] | None:
    try:
        import logging

        from urx.ursecmon import ParserUtils
    except ImportError:
        print("python-urx is not installed: pip install urx (the benchmark's comparison)")
        return None
    logging.disable(logging.CRITICAL)  # urx logs every sub-package it does not know
    return lambda d: ParserUtils().parse(d)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--messages", type=int, default=1000, help="distinct messages in the stream")
    parser.add_argument("--calls", type=int, default=500, help="calls per round of the one-message rows")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--assert-targets", action="store_true")
    args = parser.parse_args(argv)
    data = ur5e_robot_state_bytes()
    message = decode_message(data)
    baseline = baseline_decoder(data)
    assert len(baseline(data)) == len(message.sub_packages) == 13  # type: ignore[union-attr,operator]
    stream = moving_robot_stream(args.messages)
    stream12 = [without_last_sub_package(m) for m in stream]
    shared = without_last_sub_package(data)
    urx = urx_parser()
    for m in (stream[1], data):  # the same values as urx reads, and as the floor unpacks
        got = decode_message(m)
        assert baseline(m)[1][0] == got["joint_data"].joints[0].q_actual  # type: ignore[index]
        if urx is not None:
            parsed = urx(without_last_sub_package(m))
            assert parsed["JointData"]["q_actual5"] == got["joint_data"].joints[5].q_actual  # type: ignore[index]
    n, calls = len(stream), args.calls
    feeder = PrimaryStreamDecoder()
    assert [d for m in stream for _, d in feeder.feed(m)] == [decode_message(m) for m in stream]
    single = PrimaryStreamDecoder()
    unlearned = PrimaryCodec(Catalogue.builtin().spec)
    unlearned.robot_state.SHAPES_PER_SIZE = 0  # every message as a first sighting: a decoder per sub-package
    ones, ones12 = [data] * calls, [shared] * calls
    values, objects = (bound_decoder(kind, stream12[:2]) for kind in ("values", "objects"))
    bound_joints = values(stream12[5]).sub_packages[1][0]  # type: ignore[attr-defined]
    decoded = decode_message(stream12[5])
    assert isinstance(decoded, RobotStateMessage)
    assert [j[0] for j in bound_joints] == [j.q_actual for j in decoded["joint_data"].joints]
    rows: list[Row] = [
        ("struct floor: tuples, no names, no checks (13)", over(baseline, stream), n, "stream"),
        ("rtde_spec: decode_message (13)", over(decode_message, stream), n, "stream"),
        (STREAM_ROW, over(feeder.feed, stream), n, "stream"),
        ("rtde_spec: decode_message (12, the layout urx reads)", over(decode_message, stream12), n, "stream"),
        ("bound: our generated code, values in tuples, no models (12)", over(values, stream12), n, "stream"),
        (OBJECTS_ROW, over(objects, stream12), n, "stream"),
        ("struct floor: one message repeated (13)", over(baseline, ones), calls, "one"),
        ("rtde_spec: decode_message (13)", over(decode_message, ones), calls, "one"),
        ("rtde_spec: PrimaryStreamDecoder.feed (13)", over(single.feed, ones), calls, "one"),
        ("rtde_spec: decode_message (12)", over(decode_message, ones12), calls, "one"),
        ("rtde_spec: a shape not seen before (13)", over(unlearned.decode_message, ones), calls, "one"),
    ]
    if urx is not None:
        rows.insert(4, ("python-urx: ParserUtils().parse (12)", over(urx, stream12), n, "stream"))
        few = calls // 4
        rows.append(("python-urx: ParserUtils().parse (12)", over(urx, ones12[:few]), few, "one"))
    samples = interleaved_us(rows, args.rounds)
    floors = {g: samples[i] for i, (label, *_, g) in enumerate(rows) if label.startswith("struct floor")}
    urxs = {g: samples[i] for i, (label, *_, g) in enumerate(rows) if label.startswith("python-urx")}
    print(f"Robot State: {len(data)} bytes, {len(message.sub_packages)} sub-packages")  # type: ignore[union-attr]
    print(
        f"stream: {n} distinct messages of that shape, as a moving robot sends them (in every one the "
        f"sub-packages {', '.join(MOVING)} change, the rest keep their bytes); {args.rounds} rounds\n"
    )
    print(f"{'decoder, µs per message':62s} {'median':>7s} {'p90':>7s} {'/ floor':>8s} {'urx / it':>8s}")
    ratios: dict[tuple[str, str], tuple[float, float]] = {}
    for (label, *_, group), row in zip(rows, samples, strict=True):
        if label.startswith("struct floor") and group == "one":
            print("\none message, repeated (its sub-packages never change: every one reused)")
        to_floor = statistics.median(o / f for o, f in zip(row, floors[group], strict=True))
        peer = urxs.get(group)
        vs_urx = statistics.median(u / o for u, o in zip(peer, row, strict=True)) if peer else 0.0
        ratios[(group, label)] = (to_floor, vs_urx)
        p90 = sorted(row)[len(row) * 9 // 10]
        print(f"{label:62s} {statistics.median(row):7.1f} {p90:7.1f} {to_floor:7.2f}x {vs_urx:7.1f}x")
    ok = True
    print()
    for label in ("rtde_spec: decode_message (13)", STREAM_ROW):
        to_floor, vs_urx = ratios[("stream", label)]
        met = to_floor <= TARGET_TO_FLOOR and (urx is None or vs_urx >= TARGET_VS_URX)
        ok = ok and met
        print(
            f"{label} on the stream: {to_floor:.2f}x the floor (target <= {TARGET_TO_FLOOR}), "
            f"{vs_urx:.1f}x python-urx (target >= {TARGET_VS_URX:.0f}x): {'met' if met else 'MISSED'}"
        )
    if urx is not None:
        need = statistics.median(urxs["stream"]) / TARGET_VS_URX
        objects_us = statistics.median(samples[[r[0] for r in rows].index(OBJECTS_ROW)])
        print(
            f"{TARGET_VS_URX:.0f}x python-urx is {need:.1f} µs a message here; the model objects alone, "
            f"holding no values, take {objects_us:.1f} µs ({objects_us / need:.2f} of it)"
        )
    print(f"targets: {'met' if ok else 'MISSED'}")
    return 0 if ok or not args.assert_targets else 1


if __name__ == "__main__":
    sys.exit(main())
