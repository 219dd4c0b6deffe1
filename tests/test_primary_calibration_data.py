"""Calibration Data (Robot State sub-package 9) field by field, as UR's 5.9/5.10 interface
document (ClientInterfaces_Primary.pdf) lists it: six doubles Fx, Fy, Fz, Frx, Fry, Frz.

48 bytes is the body URSim 5.8 sends (UR's C++ client library's capture) and the 53-byte
sub-package UR's 2015 workbook gives for CB3. Other releases may send another size: the
interface's append rule keeps every one decoding and re-encoding to the same bytes (a
shorter body lists the missing fields, a longer one keeps the rest as extra bytes).
"""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables
from rtde_spec.primary.codec import PrimaryStreamDecoder, decode_message, encode_message
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

from .capture_files import Conversation, write

FIELDS = ("fx", "fy", "fz", "frx", "fry", "frz")
VALUES = (0.5, -0.25, 1.0, 0.0, 2.0, -3.5)
BODY = struct.pack(">6d", *VALUES)
ADDITIONAL_INFO = (8, struct.pack(">B??B", 0, True, False, 2))
TOOL_COMM_INFO = (11, struct.pack(">?iiiff", True, 115200, 0, 1, 1.5, 3.5))


def robot_state(*parts: tuple[int, bytes]) -> bytes:
    body = b"".join(struct.pack(">IB", 5 + len(b), kind) + b for kind, b in parts)
    return struct.pack(">IB", 5 + len(body), 16) + body


def decoded(data: bytes) -> tuple[RobotStateMessage, PrimaryPart]:
    message = decode_message(data)
    assert isinstance(message, RobotStateMessage)
    (part,) = (p for p in message.sub_packages if p.NAME == "calibration_data")
    assert isinstance(part, PrimaryPart)
    return message, part


def test_the_48_byte_body_is_six_doubles_that_re_encode_byte_identical() -> None:
    data = robot_state(ADDITIONAL_INFO, (9, BODY), TOOL_COMM_INFO)
    message, part = decoded(data)
    assert part.values() == dict(zip(FIELDS, VALUES, strict=True))
    assert (part.extra, part.missing) == (b"", ())
    assert encode_message(message) == data


def test_a_stream_of_5_8_reads_the_fields_without_a_warning() -> None:
    version = struct.pack(">QbB", 0, -2, 3) + b"\x09URControl" + struct.pack(">BBii", 5, 8, 0, 0) + b"date"
    data = struct.pack(">IB", 5 + len(version), 20) + version + robot_state((9, BODY))
    decoder = PrimaryStreamDecoder()
    (_, _version_message), (_, state) = decoder.feed(data)
    assert isinstance(state, RobotStateMessage)
    assert decoder.version is not None and (decoder.version.major, decoder.version.minor) == (5, 8)
    (part,) = state.sub_packages
    assert isinstance(part, PrimaryPart) and part.values()["frz"] == -3.5
    assert decoder.warnings_for(state) == []


@pytest.mark.parametrize("size", [0, 4, 40, 47])
def test_a_shorter_body_decodes_what_it_holds_and_lists_the_rest_missing(size: int) -> None:
    body = BODY[:size]  # 4: the current document's `uint32_t reserved`
    data = robot_state(ADDITIONAL_INFO, (9, body), TOOL_COMM_INFO)
    message, part = decoded(data)
    whole = size // 8
    assert part.missing == FIELDS[whole:]
    assert [part.values()[f] for f in FIELDS] == [*VALUES[:whole], *[None] * (6 - whole)]
    assert part.extra == body[8 * whole :]  # a part of a double is kept, not dropped
    assert encode_message(message) == data
    assert message.sub_packages[2].values()["baud_rate"] == 115200  # the next sub-package is intact


@pytest.mark.parametrize("tail", [b"\x01", struct.pack(">d", 9.0) + b"\x7f"])
def test_a_longer_body_keeps_the_rest_as_extra_bytes(tail: bytes) -> None:
    data = robot_state(ADDITIONAL_INFO, (9, BODY + tail), TOOL_COMM_INFO)
    message, part = decoded(data)
    assert part.values() == dict(zip(FIELDS, VALUES, strict=True))
    assert (part.extra, part.missing) == (tail, ())
    assert encode_message(message) == data
    assert message.sub_packages[2].values()["baud_rate"] == 115200


def calibration_capture(folder: Path, bodies: list[bytes]) -> Path:
    """A secondary-port capture: one Robot State per body, each with Calibration Data."""
    conv = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 30002))
    conv.handshake()
    for body in bodies:
        conv.send("server", robot_state(ADDITIONAL_INFO, (9, body)), dt=0.1)
    return write(folder / "calibration.pcap", [conv])


def test_the_capture_table_has_a_column_per_field(tmp_path: Path) -> None:
    second = struct.pack(">6d", *(v + 1 for v in VALUES))
    tables = capture_tables(calibration_capture(tmp_path, [BODY, second]))
    rows = tables["primary_calibration_data"].to_pylist()
    assert [[row[f] for f in FIELDS] for row in rows] == [list(VALUES), [v + 1 for v in VALUES]]
    assert "data" not in tables["primary_calibration_data"].column_names
