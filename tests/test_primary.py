"""Primary/secondary interface: golden vectors, compatibility rule, round trips, bad input."""

from __future__ import annotations

import json
import struct
import sys
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rtde_spec._generated import primary_models as gen
from rtde_spec._generated import primary_structs
from rtde_spec.errors import DecodeError, EncodeError, UsageError
from rtde_spec.metamodel.schema import LayoutField
from rtde_spec.metamodel.versions import Version
from rtde_spec.primary.codec import (
    PrimaryStreamDecoder,
    decode_message,
    decode_stream,
    default_codec,
    encode_message,
)
from rtde_spec.wire.primary_base import (
    OpaqueMessage,
    PrimaryPart,
    RobotStateMessage,
    UnknownMember,
    UnknownMessage,
    UnknownSubPackage,
)
from tests.budget import examples

from .helpers import DATA
from .primary_strategies import MEMBER_KEYS, member_strategy
from .strategies import SPEC

GOLDEN = yaml.safe_load((DATA / "primary_golden.yaml").read_text())


def plain(value: Any) -> Any:
    """Models, tuples and construct containers as plain dicts and lists; bytes as hex."""
    if hasattr(value, "model_dump"):
        value = value.model_dump()
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items() if not str(k).startswith("_")}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, bytes):
        return value.hex()
    return value


def _part(message: Any) -> Any:
    if isinstance(message, RobotStateMessage):
        (sub,) = message.sub_packages
        return sub
    return message


@pytest.mark.parametrize("version", ["bogus", "v5.4", "5", 5])
def test_a_controller_version_that_is_no_version_is_a_usage_error(version: object) -> None:
    """decode_message, encode_message and the stream decoder raised a bare ValueError for a
    version string that is no version; it is a UsageError now (and still a ValueError)."""
    message = gen.TextMessage(timestamp=1, source=-2, text_message="hi")
    calls = (
        lambda: decode_message(encode_message(message), version=version),  # type: ignore[arg-type]
        lambda: encode_message(message, version=version),  # type: ignore[arg-type]
        lambda: PrimaryStreamDecoder(version=version),  # type: ignore[arg-type]
    )
    for call in calls:
        with pytest.raises(UsageError, match=f"bad version string {version!r}") as info:
            call()
        assert isinstance(info.value, ValueError)


@pytest.mark.parametrize("case", GOLDEN, ids=[c["message"] for c in GOLDEN])
def test_golden_vector(case: dict[str, Any]) -> None:
    data = bytes.fromhex(case["hex"])
    message = decode_message(data)
    part = _part(message)
    assert part.NAME == case["message"] or (
        isinstance(part, OpaqueMessage) and part.family == case["message"]
    )
    if isinstance(part, PrimaryPart):
        assert (part.extra, part.missing) == (b"", ())
        assert plain(part.values()) == case["fields"]
        # the unvalidated fast build equals what pydantic validation makes of the same values
        assert type(part).model_validate(part.model_dump()) == part
    else:
        assert plain(part.raw) == case["fields"]["raw"]
    # every message encodes back to its bytes, except forms the spec reads but does not write
    assert encode_message(message).hex() == case.get("encodes_as", case["hex"])


def test_golden_vectors_cover_every_member() -> None:
    covered = {c["message"] for c in GOLDEN}
    assert {cls.NAME for cls in gen.MEMBERS.values()} <= covered
    assert "modbus_info_message" in covered


def _construct_view(fields: list[LayoutField], container: Any) -> dict[str, Any]:
    return {f.name: plain(container[f.name]) for f in fields if f.kind != "values"}


@pytest.mark.parametrize("case", GOLDEN, ids=[c["message"] for c in GOLDEN])
def test_generated_construct_structs_agree(case: dict[str, Any]) -> None:
    data = bytes.fromhex(case["hex"])
    fam = next((f for f in SPEC.primary.families if any(m.name == case["message"] for m in f.members)), None)
    if fam is None:
        assert case["message"] == "modbus_info_message"
        return
    member = next(m for m in fam.members if m.name == case["message"])
    body = data[10:] if fam.layout == "subpackages" else data[5:]
    struct_ = getattr(primary_structs, f"{fam.name.upper()}_{member.name.upper()}")
    parsed = struct_.parse(body)
    fields = [*fam.prefix, *member.fields]
    expected = {k: v for k, v in case["fields"].items() if k != "variable_values"}
    assert _construct_view(fields, parsed) == expected


@pytest.mark.parametrize("key", MEMBER_KEYS, ids=[f"{f}-{t}" for f, t in MEMBER_KEYS])
def test_round_trip_every_model(key: tuple[str, int]) -> None:
    @settings(max_examples=examples(60), deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(member_strategy(*key))
    def check(part: PrimaryPart) -> None:
        data = encode_message(part)
        assert int.from_bytes(data[:4], "big") == len(data)
        assert _part(decode_message(data)) == part

    check()


def _robot_mode_body() -> bytes:
    case = next(c for c in GOLDEN if c["message"] == "robot_mode_data")
    return bytes.fromhex(case["hex"])[10:]


def _state(*subs: bytes) -> bytes:
    body = b"".join(subs)
    return struct.pack(">IB", 5 + len(body), 16) + body


def _sub(stype: int, body: bytes) -> bytes:
    return struct.pack(">IB", 5 + len(body), stype) + body


def test_longer_subpackage_keeps_extra_bytes() -> None:
    data = _state(_sub(0, _robot_mode_body() + b"NEW!"))
    part = _part(decode_message(data))
    assert part.extra == b"NEW!" and part.missing == () and part.robot_mode == 7
    assert encode_message(decode_message(data)) == data


def test_shorter_subpackage_lists_missing_fields() -> None:
    body = _robot_mode_body()[:25]  # timestamp 8, 7 bools, 2 modes, target_speed_fraction 8
    data = _state(_sub(0, body))
    part = _part(decode_message(data))
    assert part.target_speed_fraction == 1.0
    assert part.missing == ("speed_scaling", "target_speed_fraction_limit", "reserved")
    assert part.speed_scaling is None
    assert encode_message(decode_message(data)) == data
    cut = _state(_sub(0, _robot_mode_body()[:20]))  # inside target_speed_fraction
    part = _part(decode_message(cut))
    assert part.missing[0] == "target_speed_fraction" and part.extra == _robot_mode_body()[17:20]
    assert encode_message(decode_message(cut)) == cut


def test_unknown_types_are_kept() -> None:
    state = _state(_sub(0, _robot_mode_body()), _sub(99, b"future"))
    message = decode_message(state)
    unknown = message.sub_packages[1]
    assert isinstance(unknown, UnknownSubPackage) and (unknown.type, unknown.size) == (99, 11)
    assert unknown.raw.endswith(b"future")
    assert encode_message(message) == state
    other = struct.pack(">IB", 8, 77) + b"abc"
    got = decode_message(other)
    assert isinstance(got, UnknownMessage) and (got.type, got.size, got.raw) == (77, 8, other)
    assert encode_message(got) == other
    member = struct.pack(">IBQbB", 18, 20, 5, -2, 200) + b"zzz"
    got = decode_message(member)
    assert isinstance(got, UnknownMember) and got.type == 200 and got.raw == b"zzz"
    assert got.prefix == {"timestamp": 5, "source": -2, "robot_message_type": 200}
    assert encode_message(got) == member


@pytest.mark.parametrize(
    "data,field,offset,reason",
    [
        ("0000", "size", 2, "too short"),
        ("00000003 10", "size", 0, "smaller than the header"),
        ("00000009 10 0000", "size", 7, "truncated"),
        ("7fffffff 10", "size", 0, "larger than any message"),
        ("0000000a 10 00000003 00", "size", 5, "smaller than its header"),
        ("0000000a 10 00000009 00", "size", 5, "runs past the end"),
        ("00000008 10 000000", "size", 5, "header cut off"),
        ("00000008 14 000000", None, None, "ends inside its prefix"),
    ],
)
def test_bad_framing(data: str, field: str | None, offset: int | None, reason: str) -> None:
    with pytest.raises(DecodeError) as info:
        decode_message(bytes.fromhex(data.replace(" ", "")))
    assert reason in str(info.value)
    if field is not None:
        assert (info.value.field, info.value.offset) == (field, offset)


def test_length_prefix_past_the_end_names_field_and_offset() -> None:
    body = struct.pack(">QbB", 1, -2, 3) + b"\x09URC"  # project name says 9 bytes, 3 follow
    data = struct.pack(">IB", 5 + len(body), 20) + body
    with pytest.raises(DecodeError) as info:
        decode_message(data)
    err = info.value
    assert (err.package, err.field, err.offset) == ("version_message", "project_name", 15)


def test_global_variable_errors() -> None:
    bad_type = struct.pack(">QBH", 1, 1, 0) + b"\x63\n"
    with pytest.raises(DecodeError, match="unknown global variable type 99"):
        decode_message(struct.pack(">IB", 5 + len(bad_type), 25) + bad_type)
    no_sep = struct.pack(">QBH", 1, 1, 0) + b"\x0d\x01"
    with pytest.raises(DecodeError, match="separator"):
        decode_message(struct.pack(">IB", 5 + len(no_sep), 25) + no_sep)
    deep = b"\x11\x00\x01" * 40 + b"\x00"
    body = struct.pack(">QBH", 1, 1, 0) + deep + b"\n"
    with pytest.raises(DecodeError, match="nest too deeply"):
        decode_message(struct.pack(">IB", 5 + len(body), 25) + body)


@settings(max_examples=examples(400), deadline=None)
@given(st.binary(max_size=120), st.sampled_from([5, 16, 20, 25, 99]))
def test_garbage_raises_only_decode_error(body: bytes, mtype: int) -> None:
    data = struct.pack(">IB", 5 + len(body), mtype) + body
    try:
        message = decode_message(data)
    except DecodeError as exc:
        assert str(exc)
    else:  # what decodes also encodes back to the same bytes
        assert encode_message(message) == data
    try:
        list(decode_stream(body))
    except DecodeError:
        pass


@settings(max_examples=examples(100), deadline=None)
@given(st.data())
def test_stream_independent_of_read_boundaries(data: st.DataObject) -> None:
    picks = data.draw(st.lists(st.sampled_from(GOLDEN), min_size=1, max_size=8))
    stream = b"".join(bytes.fromhex(c["hex"]) for c in picks)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=12)))
    decoder = PrimaryStreamDecoder()
    got = []
    prev = 0
    for cut in [*cuts, len(stream)]:
        got += decoder.feed(stream[prev:cut])
        prev = cut
    decoder.close()
    assert [encode_message(m).hex() for _, m in got] == [c.get("encodes_as", c["hex"]) for c in picks]


def test_version_message_sets_the_version_context() -> None:
    version = next(c for c in GOLDEN if c["message"] == "version_message")
    decoder = PrimaryStreamDecoder()
    assert decoder.version is None
    decoder.feed(bytes.fromhex(version["hex"]))
    assert decoder.version == Version(5, 15, 0)


def test_oversized_size_claim_is_refused_before_buffering() -> None:
    decoder = PrimaryStreamDecoder()
    with pytest.raises(DecodeError, match="larger than any message"):
        decoder.feed(b"\xff\xff\xff\xff\x10")
    assert decoder.framer.pending <= 5


def test_encode_errors() -> None:
    with pytest.raises(EncodeError) as info:
        gen.ToolModeInfo(output_mode=300)
    assert (info.value.field, info.value.expected) == ("output_mode", "0..255")
    with pytest.raises(EncodeError, match="earlier field"):
        encode_message(gen.ToolModeInfo(output_mode=1, digital_output_mode_pin1=2))
    with pytest.raises(EncodeError, match="at least 6 items"):
        gen.JointData(joints=())


@pytest.mark.parametrize("case", GOLDEN, ids=[c["message"] for c in GOLDEN])
def test_every_truncation_of_a_golden_message_is_a_decode_error(case: dict[str, Any]) -> None:
    data = bytes.fromhex(case["hex"])
    for cut in range(len(data)):
        with pytest.raises(DecodeError) as info:
            decode_message(data[:cut])
        assert info.value.offset is not None and info.value.field in ("size", "type")
    decoder = PrimaryStreamDecoder()
    assert decoder.feed(data[:-1]) == []
    with pytest.raises(DecodeError, match="ends inside a package"):
        decoder.close()


def test_ur5e_like_robot_state_of_the_benchmark() -> None:
    import sys

    from .helpers import ROOT

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from ur5e_robot_state import ur5e_robot_state_bytes
    finally:
        sys.path.pop(0)
    data = ur5e_robot_state_bytes()
    message = decode_message(data)
    assert [s.NAME for s in message.sub_packages] == [
        "robot_mode_data", "joint_data", "cartesian_info", "kinematics_info", "configuration_data",
        "masterboard_data", "tool_data", "force_mode_data", "additional_info", "safety_data",
        "tool_comm_info", "tool_mode_info", "cumulative_runtime_data",
    ]  # fmt: skip
    assert all(not s.missing and not s.extra for s in message.sub_packages)
    assert 1200 < len(data) < 1500
    assert message["joint_data"].joints[5].joint_mode == 253
    assert message["robot_mode_data"].robot_mode == 7
    assert encode_message(message) == data


STATE_KEYS = [key for key in MEMBER_KEYS if key[0] == "robot_state"]


@pytest.mark.parametrize("key", STATE_KEYS, ids=[f"{f}-{t}" for f, t in STATE_KEYS])
def test_compiled_sub_package_decoder_equals_the_layout_walk(key: tuple[str, int]) -> None:
    """The generated straight-line decoder of a sub-package gives the general path's model."""
    codec = default_codec()
    cls, layout = codec.families[16].members[key[1]]
    fast = codec.robot_state.fast.get(key[1])
    assert fast is not None, f"{cls.NAME} has no compiled decoder"

    @settings(max_examples=examples(40), deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(member_strategy(*key), st.binary(max_size=6), st.integers(0, 400))
    def check(part: PrimaryPart, tail: bytes, cut: int) -> None:
        body = encode_message(part)[10:] + tail  # after the message and sub-package headers
        walked = codec._part(cls, layout, body, 0, len(body), {})
        got = fast(body, 0, len(body))
        assert got == walked
        if layout.fixed_size is not None:  # a rest-of-part field takes the tail; otherwise it is extra
            assert got.extra == tail
        assert type(got).model_validate(got.model_dump()) == got  # what validation makes of it
        short = body[: min(cut, len(body))]
        general = codec._part(cls, layout, short, 0, len(short), {})
        compiled = fast(short, 0, len(short))
        assert compiled is None if general.missing else compiled == general  # None: the walk decides

    check()


def test_decoded_models_behave_as_validated_ones_for_pydantic_operations() -> None:
    """Decoded models leave pydantic's bookkeeping slots unset (PrimaryModel.__getattr__
    answers for them): equality both ways, copies, pickling, dumps and fields-set match a
    model built by validation, and unknown attributes still raise."""
    import copy
    import pickle

    from .helpers import ROOT

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from ur5e_robot_state import ur5e_robot_state_bytes
    finally:
        sys.path.pop(0)
    message = decode_message(ur5e_robot_state_bytes())
    parts = [type(s).model_validate(s.model_dump()) for s in message.sub_packages]
    twin = RobotStateMessage(sub_packages=parts)
    for decoded, validated in [(message, twin), *zip(message.sub_packages, twin.sub_packages, strict=True)]:
        assert decoded == validated and validated == decoded
        assert decoded.model_fields_set == validated.model_fields_set == set(type(decoded).model_fields)
        assert decoded.model_dump() == validated.model_dump()
        assert json.loads(decoded.model_dump_json()) == json.loads(validated.model_dump_json())
        assert decoded.model_dump(exclude_unset=True) == validated.model_dump(exclude_unset=True)
        for other in (copy.copy(decoded), copy.deepcopy(decoded), pickle.loads(pickle.dumps(decoded))):
            assert other == validated and other.model_dump() == validated.model_dump()
        assert repr(decoded).startswith(type(validated).__name__ + "(")
        with pytest.raises(AttributeError, match="no attribute 'not_a_field'"):
            decoded.not_a_field  # noqa: B018
    joints = message["joint_data"].joints
    assert "JointState(q_actual=0.5, q_target=0.25" in repr(message)
    assert joints[0] == twin["joint_data"].joints[0] != joints[0].model_copy(update={"q_actual": 9.0})
    moved = message["joint_data"].model_copy(update={"extra": b"\x01"})
    assert moved.extra == b"\x01" and moved.joints == joints
    with pytest.raises(Exception, match="frozen"):
        joints[0].q_actual = 1.0  # type: ignore[misc]


# --- the client as the README shows it (issue 21.1) ----------------------------------------------


def test_primary_client_yields_messages_and_offsets_on_request() -> None:
    from rtde_spec import EmulatorConfig, EmulatorThread, PrimaryClient
    from rtde_spec.primary.events import describe_message

    emu = EmulatorThread(
        EmulatorConfig(rtde_port=0, primary_port=0, secondary_port=0, realtime_port=None, dashboard_port=None)
    ).start()
    try:
        with PrimaryClient("127.0.0.1", emu.ports["secondary"], timeout=10) as robot:
            first = next(iter(robot))
            assert first.NAME == "version_message" and robot.last_offset == 0
            line = describe_message(first)
            assert line is not None and line.startswith("version  URControl") and "(" not in line[:9]
            state = next(iter(robot))
            assert isinstance(state, RobotStateMessage) and describe_message(state) is None
        with PrimaryClient("127.0.0.1", emu.ports["secondary"], timeout=10) as robot:
            pairs = robot.messages(with_offsets=True)
            (o1, m1), (o2, m2) = next(pairs), next(pairs)
            assert (o1, m1.NAME) == (0, "version_message") and isinstance(m2, RobotStateMessage)
            assert o2 == len(encode_message(m1)) and robot.last_offset == o2
    finally:
        emu.stop()


def test_a_primary_client_reconnects_from_a_clean_stream_and_names_a_lost_connection() -> None:
    """Iterating again after close() reconnected, but framed the new stream after the bytes of a
    message the old connection had half sent (a DecodeError of made-up size); send_script on a
    closed connection raised a bare BrokenPipeError, and bytes an AttributeError."""
    import socket
    import threading

    from rtde_spec import PrimaryClient, RtdeConnectionError

    text = encode_message(gen.TextMessage(timestamp=1, source=-2, text_message="hello"))
    with socket.create_server(("127.0.0.1", 0)) as server:

        def serve() -> None:
            for sent in (text + text[:7], text):  # the first connection ends inside a message
                peer, _ = server.accept()
                with peer:
                    peer.sendall(sent)
                    peer.recv(100)  # until the client closes or sends

        thread = threading.Thread(target=serve, daemon=True)
        thread.start()
        client = PrimaryClient("127.0.0.1", server.getsockname()[1], timeout=5)
        first = client.messages(with_offsets=True)
        assert next(first)[1].text_message == "hello"
        client.close()
        offset, again = next(client.messages(with_offsets=True))
        assert (offset, again.text_message) == (0, "hello")
        client.send_script(b"textmsg(1)")  # the server's recv returns: it closes
        thread.join(5)
        with pytest.raises(RtdeConnectionError, match="connection lost while sending"):
            for _ in range(50):  # the first send after the close may still be taken by the kernel
                client.send_script("textmsg(1)")
        client.close()


def test_describe_message_refuses_an_offset_message_pair() -> None:
    from rtde_spec.errors import UsageError
    from rtde_spec.primary.events import StateChanges, describe_message

    case = next(c for c in GOLDEN if c["message"] == "version_message")
    pair = next(iter(decode_stream(bytes.fromhex(case["hex"]))))
    assert isinstance(pair, tuple)
    with pytest.raises(UsageError, match=r"unpack the \(offset, message\) pairs"):
        describe_message(pair)
    with pytest.raises(UsageError, match=r"StateChanges\.update takes one decoded message"):
        StateChanges().describe(pair)
    assert describe_message(pair[1]) is not None


CB2 = {  # a 1.8 controller's Robot State sub-packages, in the layouts before 3.0
    "masterboard_data": "00000043100000003e030001000101013ff80000000000003ff800000000000001013ff8"
    "0000000000003ff80000000000003fc000003fc000003fc000003fc0000001",
    "robot_mode_data": "00000034100000002f00000000000001e2400101010000010007003ff00000000000003fe0"
    "0000000000003ff000000000000000",
}


@pytest.mark.parametrize("name", sorted(CB2))
def test_a_message_decoded_with_an_older_layout_encodes_back_with_the_same_version(name: str) -> None:
    """encode_message always wrote the newest layout: a CB2 masterboard decoded with 1.8 encoded
    to bytes that read back as other values (safety mode 63), and a CB2 robot mode was refused.
    With the version it was decoded with, it encodes to the bytes it came from."""
    data = bytes.fromhex(CB2[name])
    message = decode_message(data, version="1.8")
    assert type(message.sub_packages[0]).NAME == name
    assert encode_message(message, version="1.8") == data
    assert encode_message(message, version=Version(1, 8, 0)) == data
    decoder = PrimaryStreamDecoder(version="1.8")
    ((_, streamed),) = decoder.feed(data)
    assert encode_message(streamed, version=decoder.version) == data


def test_a_message_of_the_costliest_values_stays_within_its_stated_multiple() -> None:
    """Empty lists cost the most objects per wire byte (3 bytes, an object, its dict and a list
    each): primary_values.py states ~150x, and counts that cannot fit are refused before that."""
    import tracemalloc

    head = bytes.fromhex("1900000000000007d0010000")  # global variables update from index 0
    body = (b"\x11" + struct.pack(">H", 20_000) + b"\x11\x00\x00" * 20_000 + b"\n") * 3
    data = struct.pack(">I", len(head) + len(body) + 4) + head + body
    tracemalloc.start()
    try:
        message = decode_message(data)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert [len(v.value) for v in message.variable_values] == [20_000] * 3
    assert peak < 160 * len(data), peak / len(data)
    bomb = struct.pack(">I", len(head) + 9 + 4) + head + b"\x11\xff\xff" + b"\x11\x00\x00" * 2
    with pytest.raises(DecodeError, match="cannot fit in the bytes left"):
        decode_message(bomb)
