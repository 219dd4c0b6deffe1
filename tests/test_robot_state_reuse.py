"""Robot State model reuse: a sub-package whose bytes equal the last one in its slot is handed
out as the same frozen model; every result must equal a decode without reuse, whatever
changed, and the caches stay bounded."""

from __future__ import annotations

import struct
import sys
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtde_spec.errors import DecodeError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.primary.codec import PrimaryCodec, PrimaryStreamDecoder, decode_message, encode_message
from rtde_spec.wire.primary_base import RobotStateMessage
from tests.budget import examples

from .helpers import ROOT
from .test_robot_state_shapes import _offset_of_immi_flag

sys.path.insert(0, str(ROOT / "benchmarks"))
try:
    from ur5e_robot_state import ur5e_robot_state_bytes
finally:
    sys.path.pop(0)

BASE = ur5e_robot_state_bytes()


def fresh() -> PrimaryCodec:
    return PrimaryCodec(Catalogue.builtin().spec)


def plain() -> PrimaryCodec:
    """A codec that never learns a shape: every message walked, nothing reused."""
    codec = fresh()
    codec.robot_state.SHAPES_PER_SIZE = 0
    return codec


PLAIN = plain()


def subs(message: Any) -> list[Any]:
    assert isinstance(message, RobotStateMessage)
    return message.sub_packages


def bounds(data: bytes) -> list[tuple[int, int]]:
    """(start, end) of every sub-package (header included)."""
    pos, out = 5, []
    while pos < len(data):
        size = struct.unpack_from(">I", data, pos)[0]
        out.append((pos, pos + size))
        pos += size
    return out


def with_joints_moved(data: bytes, step: float) -> bytes:
    """`data` with every joint's position and current moved by `step`: only joint data changes."""
    message = decode_message(data)
    parts = [
        p.model_copy(
            update={
                "joints": tuple(
                    j.model_copy(update={"q_actual": j.q_actual + step, "i_actual": j.i_actual - step})
                    for j in p.joints
                )
            }
        )
        if p.NAME == "joint_data"
        else p
        for p in subs(message)
    ]
    return encode_message(RobotStateMessage(sub_packages=parts))


def learned(codec: PrimaryCodec, data: bytes) -> Any:
    """Decode `data` until its shape is compiled and used; the last result."""
    for _ in range(3):
        got = codec.decode_message(data)
    assert codec.robot_state.shapes[len(data) - 5]
    return got


def test_only_the_changed_sub_package_is_a_new_model() -> None:
    moved = with_joints_moved(BASE, 0.125)
    names = [p.NAME for p in subs(decode_message(BASE))]
    assert moved != BASE and len(moved) == len(BASE)
    reference = subs(PLAIN.decode_message(moved))
    codec = fresh()
    before = subs(learned(codec, BASE))
    stream = PrimaryStreamDecoder(fresh())
    for _ in range(3):
        ((_, streamed),) = stream.feed(BASE)
    for got, previous in (
        (subs(codec.decode_message(moved)), before),
        (subs(stream.feed(moved)[0][1]), subs(streamed)),
    ):
        assert got == reference
        for name, new, old in zip(names, got, previous, strict=True):
            if name == "joint_data":
                assert new is not old and new != old
            else:
                assert new is old
    # and back: the first message again is equal to its uncached decode, joint data new again
    again = subs(codec.decode_message(BASE))
    assert again == subs(PLAIN.decode_message(BASE)) and again[1] is not before[1]


def test_a_stream_decoder_keeps_its_own_cache() -> None:
    """Two stream decoders and decode_message on one codec do not hand out each other's models."""
    codec = fresh()
    learned(codec, BASE)
    one, two = PrimaryStreamDecoder(codec), PrimaryStreamDecoder(codec)
    for _ in range(3):
        ((_, a),) = one.feed(BASE)
        ((_, b),) = two.feed(BASE)
    shared = codec.decode_message(BASE)
    assert a == b == shared
    assert all(x is not y for x, y in zip(subs(a), subs(b), strict=True))
    assert all(x is not y for x, y in zip(subs(a), subs(shared), strict=True))


@settings(max_examples=examples(120), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_one_changed_byte_anywhere_in_a_sub_package_gives_a_new_correct_model(data: st.DataObject) -> None:
    parts = bounds(BASE)
    slot = data.draw(st.integers(0, len(parts) - 1))
    start, end = parts[slot]
    at = data.draw(st.integers(start + 5, end - 1))  # its body: the headers are the damage test's
    value = data.draw(st.integers(0, 255).filter(lambda v: v != BASE[at]))
    changed = bytearray(BASE)
    changed[at] = value
    codec = fresh()
    stream = PrimaryStreamDecoder(codec)
    before = subs(learned(codec, BASE))
    for _ in range(3):
        ((_, streamed),) = stream.feed(BASE)
    reference = repr(PLAIN.decode_message(bytes(changed)))  # repr: a changed double may be NaN
    immi = 5 + _offset_of_immi_flag()
    walked = parts[slot][0] + immi == at and BASE[at] == 0  # the IMMI group "present", its bytes absent
    for got, previous in (
        (codec.decode_message(bytes(changed)), before),
        (stream.feed(bytes(changed))[0][1], subs(streamed)),
    ):
        assert repr(got) == reference
        assert subs(got)[slot] is not previous[slot]
        if not walked:
            others = [(g, p) for i, (g, p) in enumerate(zip(subs(got), previous, strict=True)) if i != slot]
            assert all(g is p for g, p in others)
    assert repr(codec.decode_message(BASE)) == repr(PLAIN.decode_message(BASE))  # the cache is not spoilt


def outcome(decode: Any, data: bytes) -> str:
    try:
        return repr(decode(data))
    except DecodeError as exc:
        return f"error: {exc}"


@settings(max_examples=examples(150), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    st.lists(st.tuples(st.integers(0, 1331), st.integers(0, 255)), min_size=1, max_size=6),
    st.booleans(),
)
def test_damaged_messages_decode_as_without_reuse(edits: list[tuple[int, int]], strict: bool) -> None:
    """Bytes changed anywhere (headers included) after the caches hold the undamaged message's
    models: the result, or the error, is the one a codec without shapes or reuse gives, and the
    undamaged message decodes right after."""
    damaged = bytearray(BASE)
    for at, value in edits:
        damaged[at % len(BASE)] = value
    if not strict:
        damaged += b"\x00\x01"  # bytes after the message, ignored when not strict
    codec = fresh()
    learned(codec, BASE)
    stream = PrimaryStreamDecoder(codec, skip_errors=True)
    without = PrimaryStreamDecoder(PLAIN, skip_errors=True)
    for _ in range(3):
        stream.feed(BASE)
        without.feed(BASE)
    expected = outcome(lambda d: PLAIN.decode_message(d, strict=strict), bytes(damaged))
    assert outcome(lambda d: codec.decode_message(d, strict=strict), bytes(damaged)) == expected
    if struct.unpack_from(">I", damaged)[0] == len(damaged):  # framed as one message
        fed, reference = stream.feed(bytes(damaged)), without.feed(bytes(damaged))
        assert repr(fed) == repr(reference) and stream.skipped == without.skipped
        assert (repr(fed[0][1]) if fed else f"error: {stream.skipped.first[-1][1]}").startswith(expected[:40])
    for decode in (codec.decode_message, lambda d: stream.feed(d)[0][1]):
        assert repr(decode(BASE)) == repr(PLAIN.decode_message(BASE))


def test_caches_stay_bounded_over_ten_thousand_distinct_messages() -> None:
    """Every message new (timestamp and a joint position): each cache keeps one model and its bytes
    per sub-package; a stream of ever other shapes keeps at most REUSE_SHAPES caches."""
    codec = fresh()
    stream = PrimaryStreamDecoder(codec)
    (start, _), (joints, _) = bounds(BASE)[:2]
    message = bytearray(BASE)
    for i in range(10_000):
        struct.pack_into(">Q", message, start + 5, i)  # robot mode timestamp
        struct.pack_into(">d", message, joints + 5, i / 7)  # joint 0 q_actual
        data = bytes(message)
        got = codec.decode_message(data)
        fed = stream.feed(data)[0][1]
        if i % 2500 == 0:
            assert got == fed == PLAIN.decode_message(data)
    (shape,) = codec.robot_state.shapes[len(BASE) - 5]
    for cache in (shape.shared, stream.reuse[shape]):
        assert len(cache) == len(bounds(BASE))
        assert sum(len(held) for held, _ in cache) == len(BASE) - 5  # one message's bytes, no more
    assert list(stream.reuse) == [shape]
    # ever other shapes: sub-packages of other sizes (each seen twice, so compiled)
    tool = bounds(BASE)[6]
    for extra in range(1, 40):
        body = BASE[tool[0] : tool[1]] + bytes(extra)  # tool data with `extra` bytes after its layout
        sub = struct.pack(">I", len(body)) + body[4:]
        data = struct.pack(">IB", 5 + len(sub), 16) + sub
        for _ in range(3):
            assert stream.feed(data)[0][1] == PLAIN.decode_message(data)
    assert len(stream.reuse) <= codec.robot_state.REUSE_SHAPES
