"""Every package layout against hand-computed bytes from the guides."""

from __future__ import annotations

import pytest

from rtde_spec._generated import rtde_models as gen
from rtde_spec.rtde.codec import decode, message_by_name

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
