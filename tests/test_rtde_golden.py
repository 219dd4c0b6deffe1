"""Every package layout against hand-computed bytes from the guides."""

from __future__ import annotations

import pytest

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError
from rtde_spec.rtde.codec import build, decode, message_by_name, model_of
from rtde_spec.rtde.packages import decode_package, encode_package

from .helpers import assert_package, expected_values, golden

CASES = golden()


@pytest.mark.parametrize("case", CASES, ids=[f"{c['package']}-{i}" for i, c in enumerate(CASES)])
def test_golden_vector(case: dict) -> None:
    data = bytes.fromhex(case["hex"].replace(" ", ""))
    message = decode(data, sender=case["sender"], protocol_version=case["protocol"])
    assert message.NAME == case["package"]
    assert message.fields() == expected_values(case["package"], case["fields"])
    assert_package(data, message, case["sender"], case["protocol"])


def test_golden_vectors_cover_every_layout() -> None:
    covered = {case["package"] for case in CASES}
    assert covered == {cls.NAME for cls in gen.MESSAGES}


def test_every_type_sender_protocol_has_exactly_one_layout() -> None:
    for code in gen.PACKAGE_TYPES:
        for sender in gen.SENDERS:
            for proto in gen.PROTOCOLS:
                cls = gen.BY_KEY.get((code, sender, proto))
                # every package type is sent by the client; the controller answers all but U/M
                # with a reply, and sends U and M itself
                assert cls is not None, (chr(code), sender, proto)


def test_protocol_1_text_message_layout_depends_on_sender() -> None:
    assert message_by_name("text_message_v1_controller").FIELDS[0] == "message_type"
    assert message_by_name("text_message_v1_client").FIELDS[0] == "message"


@pytest.mark.parametrize("case", CASES, ids=[f"{c['package']}-{i}" for i, c in enumerate(CASES)])
def test_the_plain_path_reads_and_writes_every_package_as_the_models_do(case: dict) -> None:
    """Capture and the clients decode and build packages without the models (rtde.packages):
    same name, type and values (types included) as the model, and the same bytes back."""
    data = bytes.fromhex(case["hex"].replace(" ", ""))
    package = decode_package(data, sender=case["sender"], protocol_version=case["protocol"])
    message = decode(data, sender=case["sender"], protocol_version=case["protocol"])
    assert (package.name, package.package_type) == (message.NAME, message.PACKAGE_TYPE)
    assert package.values == message.fields()
    assert [type(v) for v in package.values.values()] == [type(v) for v in message.fields().values()]
    assert encode_package(package.name, package.values) == data
    assert model_of(package.name, package.values) == message


def test_the_plain_path_and_the_models_refuse_alike() -> None:
    """A cut package, an unknown type, bytes after the last field: the same error either way."""
    whole = build("setup_outputs_v2", output_frequency=125.0, variable_names=["timestamp"])
    version = build("request_protocol_version", protocol_version=2)  # the reply's layout is shorter
    for data, sender in ((whole[:-3], "client"), (b"\x00\x03Z", "controller"), (version, "controller")):
        with pytest.raises(DecodeError) as plain_error:
            decode_package(data, sender=sender)
        with pytest.raises(DecodeError) as model_error:
            decode(data, sender=sender)  # type: ignore[arg-type]
        assert str(plain_error.value) == str(model_error.value)
        assert (plain_error.value.field, plain_error.value.offset) == (
            model_error.value.field, model_error.value.offset
        )  # fmt: skip


def test_the_layouts_the_decoders_act_on_are_the_specs() -> None:
    """Capture, the session decoder and the client core pick packages by these spec names."""
    from rtde_spec.rtde import packages

    named = {
        packages.DATA,
        packages.VERSION_REQUEST,
        packages.VERSION_REPLY,
        packages.CONTROLLER_VERSION_REPLY,
    }
    named |= packages.TEXTS | packages.SETUP_REQUESTS.keys() | packages.SETUP_REPLIES.keys()
    assert named <= {cls.NAME for cls in gen.MESSAGES}
    assert {n for n in named if "text" in n} == {cls.NAME for cls in gen.MESSAGES if "text" in cls.NAME}
    assert {n for n in named if n.startswith("setup")} == {
        c.NAME for c in gen.MESSAGES if c.NAME.startswith("setup")
    }
