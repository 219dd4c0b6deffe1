"""Bad input gets the library's error naming package, field and byte offset."""

from __future__ import annotations

import pytest

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.rtde.codec import build, decode, encode


def h(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


@pytest.mark.parametrize(
    "data,field,offset,reason",
    [
        ("00", "size", 1, "too short"),
        ("0004", "type", 2, "too short"),
        ("0002 56", "size", 0, "smaller than the header"),
        ("0000 56", "size", 0, "smaller than the header"),
        ("0009 56 01", "size", 4, "truncated"),
        ("0004 58 01", "type", 2, "unknown package type 88 ('X')"),
    ],
)
def test_header_errors(data: str, field: str, offset: int, reason: str) -> None:
    with pytest.raises(DecodeError) as info:
        decode(h(data), sender="controller")
    err = info.value
    assert (err.field, err.offset) == (field, offset)
    assert reason in str(err)


def test_truncated_field_names_package_field_and_offset() -> None:
    with pytest.raises(DecodeError) as info:
        decode(h("000b 76 00000005 0000000c"), sender="controller")
    err = info.value
    assert (err.package, err.field, err.offset) == ("get_urcontrol_version_reply", "bugfix", 11)


def test_length_prefix_past_the_package() -> None:
    with pytest.raises(DecodeError) as info:
        decode(h("0009 4d 09 6869 02 7079"), sender="client", protocol_version=2)
    err = info.value
    assert (err.package, err.field, err.offset) == ("text_message", "message", 3)
    assert "length prefix says 9 bytes" in str(err)


def test_non_ascii_name_is_located() -> None:
    with pytest.raises(DecodeError) as info:
        decode(h("0009 49 74696d65c3a9"), sender="client")
    err = info.value
    assert (err.package, err.field, err.offset) == ("setup_inputs", "variable_names", 7)
    assert "not ASCII" in str(err)


def test_trailing_bytes_are_an_error_unless_lenient() -> None:
    data = h("0005 53 01 ff")
    with pytest.raises(DecodeError) as info:
        decode(data, sender="controller")
    assert info.value.offset == 4
    assert decode(data, sender="controller", strict=False) == gen.StartReply(accepted=True)


def test_package_type_never_sent_by_that_side() -> None:
    # a data package is sent both ways, but only the controller sends setup replies;
    # the client sends setup requests: same letter, other layout. v2-only text in v1:
    with pytest.raises(DecodeError, match="unknown protocol version 3"):
        decode(h("0003 53"), sender="client", protocol_version=3)


@pytest.mark.parametrize(
    "name,fields,field,expected",
    [
        ("request_protocol_version", {"protocol_version": 70000}, "protocol_version", "0..65535"),
        (
            "setup_inputs_reply",
            {"input_recipe_id": 300, "variable_types": ["INT32"]},
            "input_recipe_id",
            "0..255",
        ),
        (
            "get_urcontrol_version_reply",
            {"major": -1, "minor": 0, "bugfix": 0, "build": 0},
            "major",
            "0..4294967295",
        ),
        (
            "text_message",
            {"message": "x" * 256, "source": "", "warning_level": 0},
            "message",
            "at most 255",
        ),
        ("text_message", {"message": "héllo", "source": "", "warning_level": 0}, "message", None),
        ("setup_inputs", {"variable_names": ["a,b"]}, "variable_names.0", None),
        ("setup_inputs", {"variable_names": []}, "variable_names", None),
        ("start", {"extra": 1}, "extra", None),
    ],
)
def test_encode_errors_name_package_field_and_bounds(
    name: str, fields: dict, field: str, expected: str | None
) -> None:
    with pytest.raises(EncodeError) as info:
        build(name, **fields)
    err = info.value
    assert (err.package, err.field) == (name, field)
    if expected:
        assert expected in str(err.expected)


def test_encode_rechecks_models_that_skipped_validation() -> None:
    bad = gen.RequestProtocolVersion.model_construct(protocol_version=-5)
    with pytest.raises(EncodeError) as info:
        encode(bad)
    assert info.value.field == "protocol_version"


def test_package_over_the_size_field() -> None:
    with pytest.raises(EncodeError) as info:
        build("data_package", recipe_id=1, payload=b"\0" * 70000)
    assert info.value.field == "size" and "65535" in str(info.value.expected)


@pytest.mark.parametrize("given", ["0005560002", 5, None])
def test_what_is_no_bytes_is_named_by_every_decoder(given: object) -> None:
    """Hex text raised TypeError "string argument without an encoding" (or "can't concat str to
    bytearray" from a stream decoder, "message cut short" from the real-time one); a number was
    decoded as that many zero bytes. Each is a UsageError saying what to pass."""
    from rtde_spec import PrimaryStreamDecoder, SessionDecoder, StreamDecoder, UsageError, decode_message
    from rtde_spec.realtime import RealtimeStream
    from rtde_spec.realtime import decode as decode_realtime
    from rtde_spec.rtde.codec import decode_stream

    calls = [
        lambda: decode(given, sender="client"),  # type: ignore[arg-type]
        lambda: decode_message(given),  # type: ignore[arg-type]
        lambda: list(decode_stream(given)),  # type: ignore[arg-type]
        lambda: list(StreamDecoder().feed(given)),  # type: ignore[arg-type]
        lambda: PrimaryStreamDecoder().feed(given),  # type: ignore[arg-type]
        lambda: SessionDecoder().feed("client", given),  # type: ignore[arg-type]
        lambda: RealtimeStream().feed(given),  # type: ignore[arg-type]
    ]
    if given is not None:
        calls.append(lambda: decode_realtime(given))  # type: ignore[arg-type]
    for call in calls:
        with pytest.raises(UsageError, match=f"takes bytes .*not {type(given).__name__}"):
            call()
    assert decode(bytearray(h("0005 56 0002")), sender="client") == decode(h("0005 56 0002"), sender="client")


def test_an_error_about_a_huge_value_shows_its_start_and_size() -> None:
    """A 70,000-character text message, or 100,000 values for a vector, were the whole error
    message; the message shows 500 characters of the value, `actual` keeps all of it."""
    from rtde_spec import RecipeCodec

    with pytest.raises(EncodeError) as info:
        build("text_message", message="x" * 70000, source="me", warning_level=1)
    assert len(str(info.value)) < 800 and "... (70002 characters)" in str(info.value)
    assert info.value.actual == repr("x" * 70000)
    with pytest.raises(EncodeError) as info:
        RecipeCodec.for_names(["actual_q"], "output").encode({"actual_q": [0.0] * 100_000})
    assert len(str(info.value)) < 900 and "100000 given" in str(info.value)
