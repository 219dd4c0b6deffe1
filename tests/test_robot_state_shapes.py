"""Robot State shapes: a message whose sub-package sizes and types were seen before is decoded
by one generated function; it must give exactly what the sub-package walk gives, and fall
back to the walk whenever the bytes do not fit the shape."""

from __future__ import annotations

import struct
from typing import Any

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.primary.codec import PrimaryCodec, decode_message, default_codec, encode_message
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage
from tests.budget import examples

from .helpers import DATA
from .primary_strategies import MEMBER_KEYS, member_strategy

GOLDEN = yaml.safe_load((DATA / "primary_golden.yaml").read_text())
STATE_TYPES = [t for f, t in MEMBER_KEYS if f == "robot_state"]
parts = st.lists(
    st.sampled_from(STATE_TYPES).flatmap(lambda t: member_strategy("robot_state", t)), max_size=8
)


def fresh() -> PrimaryCodec:
    return PrimaryCodec(Catalogue.builtin().spec)


def walked(codec: PrimaryCodec, data: bytes) -> list[Any]:
    """The sub-package walk alone (no shape), as a reference."""
    return codec.robot_state._walk(data, 5, len(data), frozenset(), None)[0]


def message(subs: list[PrimaryPart]) -> bytes:
    return encode_message(RobotStateMessage(sub_packages=subs))


@settings(max_examples=examples(60), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(parts, parts)
def test_a_learned_shape_decodes_as_the_walk_does(
    first: list[PrimaryPart], second: list[PrimaryPart]
) -> None:
    codec = fresh()
    a, b = message(first), message(second)
    for data in (a, a, a, b, b, b, a):  # learned on the second sighting, then used
        got = codec.decode_message(data)
        assert got.sub_packages == walked(codec, data)  # type: ignore[union-attr]
    shapes = codec.robot_state.shapes
    if first and all(type(s).model_fields.keys() for s in first):
        assert sum(len(v) for v in shapes.values()) >= 1


@settings(max_examples=examples(40), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(member_strategy("robot_state", 3), min_size=2, max_size=2))
def test_same_sizes_other_values_and_a_flag_the_size_does_not_carry(boards: list[PrimaryPart]) -> None:
    """Two masterboard sub-packages of the same size: the second decodes its own values; one
    whose IMMI flag says "group present" while the bytes end before it takes the walk."""
    codec = fresh()
    first, second = boards
    data = message([first])
    codec.decode_message(data)
    codec.decode_message(data)
    assert codec.robot_state.shapes  # compiled
    other = message([second])
    assert codec.decode_message(other).sub_packages == walked(codec, other)  # type: ignore[union-attr]
    flag_at = 5 + 5 + _offset_of_immi_flag()
    if len(other) == len(data) and other[flag_at] == 0:
        lying = other[:flag_at] + b"\x01" + other[flag_at + 1 :]
        got = codec.decode_message(lying).sub_packages[0]  # type: ignore[union-attr]
        assert got == walked(codec, lying)[0] and "immi" in got.missing


def _offset_of_immi_flag() -> int:
    """Bytes of the masterboard body before `immi_interface_installed` (from the spec's layout)."""
    layout = default_codec().families[16].members[3][1]
    size = 0
    for fld in layout.fields:
        if fld.name == "immi_interface_installed":
            return size
        size += layout.prims[fld.type or ""].size * (fld.count or 1)
    raise AssertionError("no IMMI flag in the masterboard layout")


def golden_part(name: str) -> PrimaryPart:
    """A sub-package from the hand-packed golden vectors (a Robot State of that one part)."""
    case = next(c for c in GOLDEN if c["message"] == name)
    return decode_message(bytes.fromhex(case["hex"])).sub_packages[0]  # type: ignore[union-attr,no-any-return]


def test_same_total_size_other_shape_and_a_cut_message_take_the_walk() -> None:
    codec = fresh()
    subs = [golden_part("robot_mode_data"), golden_part("cartesian_info")]
    forward, backward = message(subs), message(subs[::-1])
    assert len(forward) == len(backward)
    for data in (forward, forward, backward, forward):
        got = codec.decode_message(data).sub_packages  # type: ignore[union-attr]
        assert [s.NAME for s in got] == [s.NAME for s in (subs if data == forward else subs[::-1])]
        assert got == walked(codec, data)
    assert len(codec.robot_state.shapes[len(forward) - 5]) == 1  # the reversed one was seen once
    one = message([golden_part("robot_mode_data")])
    codec.decode_message(one)
    codec.decode_message(one)
    cut = bytearray(one[:-3])  # the same size fields less 3: a different shape, shorter than the layout
    struct.pack_into(">I", cut, 0, len(cut))
    struct.pack_into(">I", cut, 5, len(cut) - 5)
    got = codec.decode_message(bytes(cut)).sub_packages[0]  # type: ignore[union-attr]
    assert got.missing and got == walked(codec, bytes(cut))[0]


def test_shapes_per_size_are_bounded() -> None:
    codec = fresh()
    reader = codec.robot_state
    names = ["tool_data", "cartesian_info", "force_mode_data", "tool_comm_info", "tool_mode_info"]
    examples = [golden_part(n) for n in names]
    sizes = {len(encode_message(RobotStateMessage(sub_packages=[e]))) for e in examples}
    import itertools

    seen = 0
    for order in itertools.permutations(examples, 3):
        data = message(list(order))
        codec.decode_message(data)
        codec.decode_message(data)
        seen += 1
    assert seen > reader.SHAPES_PER_SIZE and sizes
    assert all(len(v) <= reader.SHAPES_PER_SIZE for v in reader.shapes.values())


def test_threads_sharing_a_codec_learn_shapes_without_errors() -> None:
    """The default codec is shared; threads that learn the same shapes at once get the walk's
    models, and the shapes stay bounded."""
    import threading

    codec = fresh()
    names = ["robot_mode_data", "cartesian_info", "tool_data", "force_mode_data"]
    messages = [message([golden_part(a), golden_part(b)]) for a in names for b in names]
    expected = [walked(codec, m) for m in messages]
    errors: list[BaseException] = []

    def work() -> None:
        try:
            for _ in range(30):
                for data, want in zip(messages, expected, strict=True):
                    assert codec.decode_message(data).sub_packages == want  # type: ignore[union-attr]
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert all(len(v) <= codec.robot_state.SHAPES_PER_SIZE + 3 for v in codec.robot_state.shapes.values())
    assert sum(len(v) for v in codec.robot_state.shapes.values()) >= 4


@settings(max_examples=examples(150), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, 1331), st.integers(0, 255)), min_size=1, max_size=6))
def test_damaged_bytes_of_a_learned_shape_decode_as_without_shapes(edits: list[tuple[int, int]]) -> None:
    """Bytes changed anywhere in a message whose shape is learned (headers included): the
    result, or the error, is the one a codec that never learned a shape gives."""
    import sys

    from rtde_spec.errors import DecodeError

    from .helpers import ROOT

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from ur5e_robot_state import ur5e_robot_state_bytes
    finally:
        sys.path.pop(0)
    data = ur5e_robot_state_bytes()
    learned, plain = _learned(data), fresh()
    plain.robot_state.SHAPES_PER_SIZE = 0
    damaged = bytearray(data)
    for at, value in edits:
        damaged[at % len(data)] = value
    outcomes = []
    for codec in (learned, plain):
        try:
            outcomes.append(codec.decode_message(bytes(damaged)))
        except DecodeError as exc:
            outcomes.append(str(exc))
    # repr, not ==: a damaged double may be NaN, which equals nothing, itself included
    assert repr(outcomes[0]) == repr(outcomes[1])
    assert learned.robot_state.shapes[len(data) - 5]  # the learned shape was there to try


_LEARNED: dict[bytes, PrimaryCodec] = {}


def _learned(data: bytes) -> PrimaryCodec:
    """A codec that has seen `data` twice (its shape compiled), made once per test run."""
    if data not in _LEARNED:
        codec = fresh()
        codec.decode_message(data)
        codec.decode_message(data)
        _LEARNED[data] = codec
    return _LEARNED[data]
