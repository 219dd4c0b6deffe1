"""Property tests: round trips of every package model; garbage never escapes as internals."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError
from rtde_spec.rtde.codec import decode, decode_stream, encode
from rtde_spec.wire.framing import PackageFramer
from tests.budget import examples

from .helpers import golden
from .strategies import message_strategy

SETTINGS = settings(max_examples=examples(150), deadline=None, suppress_health_check=[HealthCheck.too_slow])


@pytest.mark.parametrize("cls", gen.MESSAGES, ids=lambda c: c.NAME)
def test_round_trip_every_model(cls: type) -> None:
    @SETTINGS
    @given(message_strategy(cls))
    def check(message: gen.RtdeMessage) -> None:
        data = encode(message)
        assert int.from_bytes(data[:2], "big") == len(data)
        assert data[2] == cls.PACKAGE_TYPE
        for sender in cls.SENDERS:
            for proto in cls.PROTOCOLS:
                assert decode(data, sender=sender, protocol_version=proto) == message

    check()


@pytest.mark.parametrize("cls", [c for c in gen.MESSAGES if c.FIELDS], ids=lambda c: c.NAME)
def test_round_trip_bytes_with_nan(cls: type) -> None:
    """NaN != NaN, so compare bytes: decode then encode gives the same package."""

    @SETTINGS
    @given(message_strategy(cls, allow_nan=True))
    def check(message: gen.RtdeMessage) -> None:
        data = encode(message)
        again = decode(data, sender=cls.SENDERS[0], protocol_version=cls.PROTOCOLS[0])
        assert encode(again) == data

    check()


@settings(max_examples=examples(400), deadline=None)
@given(
    data=st.binary(max_size=80),
    sender=st.sampled_from(gen.SENDERS),
    proto=st.sampled_from(gen.PROTOCOLS),
    strict=st.booleans(),
)
def test_random_bytes_raise_only_decode_error(data: bytes, sender: str, proto: int, strict: bool) -> None:
    try:
        decode(data, sender=sender, protocol_version=proto, strict=strict)  # type: ignore[arg-type]
    except DecodeError as exc:
        assert str(exc)
    try:
        list(decode_stream(data, sender=sender, protocol_version=proto))  # type: ignore[arg-type]
    except DecodeError as exc:
        assert str(exc)


@settings(max_examples=examples(300), deadline=None)
@given(
    header=st.sampled_from(sorted(gen.PACKAGE_TYPES)),
    body=st.binary(max_size=40),
    sender=st.sampled_from(gen.SENDERS),
    proto=st.sampled_from(gen.PROTOCOLS),
)
def test_well_framed_random_bodies_raise_only_decode_error(
    header: int, body: bytes, sender: str, proto: int
) -> None:
    data = (3 + len(body)).to_bytes(2, "big") + bytes([header]) + body
    try:
        decode(data, sender=sender, protocol_version=proto)  # type: ignore[arg-type]
    except DecodeError as exc:
        assert exc.package is not None or exc.field is not None


@pytest.mark.parametrize("case", golden(), ids=lambda c: c["package"])
def test_every_truncation_of_a_golden_package_is_a_decode_error(case: dict) -> None:
    data = bytes.fromhex(case["hex"].replace(" ", ""))
    for cut in range(len(data)):
        with pytest.raises(DecodeError) as info:
            decode(data[:cut], sender=case["sender"], protocol_version=case["protocol"])
        assert info.value.offset is not None


@settings(max_examples=examples(200), deadline=None)
@given(st.data())
def test_framer_is_independent_of_read_boundaries(data: st.DataObject) -> None:
    cases = golden()
    picks = data.draw(st.lists(st.sampled_from(cases), min_size=1, max_size=12))
    stream = b"".join(bytes.fromhex(c["hex"].replace(" ", "")) for c in picks)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=20)))
    framer = PackageFramer()
    got = []
    prev = 0
    for cut in [*cuts, len(stream)]:
        got += framer.feed(stream[prev:cut])
        prev = cut
    framer.close()
    assert b"".join(p for _, p in got) == stream
    assert [o for o, _ in got] == [
        sum(len(bytes.fromhex(c["hex"].replace(" ", ""))) for c in picks[:i]) for i in range(len(picks))
    ]
