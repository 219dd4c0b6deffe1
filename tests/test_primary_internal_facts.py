"""Configuration, calibration and safety data: what public sources say, named in the spec (issue 27, item 6).

Configuration Data is decoded field by field (the document's layout, which UR's C++
client library reads the same way); from 5.25.1 the controller appends two int16
reserved fields (URCL PR #485), kept as extra bytes without a warning. Calibration Data
(9) is decoded as the 5.9/5.10 interface document (ClientInterfaces_Primary.pdf) lists it:
six doubles Fx..Frz, the 48 bytes URSim 5.8 sends. Safety Data (10) stays bytes: no public
source describes its fields, and the spec says which sources were searched. None of this
changes a byte the emulator sends.
"""

from __future__ import annotations

import struct
from pathlib import Path

from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.primary.codec import PrimaryStreamDecoder, encode_message
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

from .test_emulator_robot_state import URSIM_5_8_UR5E, messages, shape

ROOT = Path(__file__).resolve().parents[1]
MEMBERS = {m.name: m for f in load_spec(ROOT / "spec").primary.families for m in f.members}


def test_every_internal_member_names_its_sources() -> None:
    for name in ("configuration_data", "calibration_data", "safety_data", "payload_info", "internal_data"):
        assert MEMBERS[name].source, name
    assert "#485" in (MEMBERS["configuration_data"].source or "")
    assert "NEEDED_FOR_CALIB_DATA" in (MEMBERS["calibration_data"].source or "")
    pdf = "ClientInterfaces_Primary.pdf, Robot Software 5.9 and 5.10"
    assert (MEMBERS["calibration_data"].source or "").startswith(pdf)
    assert all(pdf in (f.source or "") for f in MEMBERS["calibration_data"].fields)
    assert "ClientInterfaces_Primary.pdf" in (MEMBERS["safety_data"].source or "")
    reserved = next(f for f in MEMBERS["configuration_data"].fields if f.name == "reserved")
    assert reserved.source and "controller_box_type" in reserved.source
    doc = (ROOT / "docs" / "reference" / "primary.md").read_text()
    assert doc.count("Sources: Searched, no field layout found") == 3 and "controller_box_type" in doc
    assert "Sources: ClientInterfaces_Primary.pdf, Robot Software 5.9 and 5.10" in doc


def first_state(version: str) -> tuple[bytes, bytes]:
    emu = EmulatorThread(
        EmulatorConfig(
            rtde_port=None,
            primary_port=0,
            secondary_port=0,
            realtime_port=None,
            dashboard_port=None,
            controller=version,
        )
    ).start()
    try:
        version_message, state = (m for m in messages(emu.ports["secondary"], 2))
    finally:
        emu.stop()
    return version_message, state


def test_the_5_8_robot_state_keeps_ursims_bytes_and_decodes_back_to_them() -> None:
    version_message, state = first_state("5.8.0")
    assert shape(state) == URSIM_5_8_UR5E  # calibration data 53 bytes, safety data 43
    decoder = PrimaryStreamDecoder()
    decoded = [m for _, m in decoder.feed(version_message + state)][1]
    assert isinstance(decoded, RobotStateMessage)
    assert encode_message(decoded) == state
    parts = {p.NAME: p for p in decoded.sub_packages if isinstance(p, PrimaryPart)}
    calibration = parts["calibration_data"]
    assert calibration.values() == dict.fromkeys(("fx", "fy", "fz", "frx", "fry", "frz"), 0.0)
    assert (calibration.extra, calibration.missing) == (b"", ())
    assert len(parts["safety_data"].data) == 38


def with_configuration_tail(state: bytes, tail: bytes) -> bytes:
    """The Robot State with `tail` appended to its Configuration Data, sizes fixed up."""
    out, pos = bytearray(state[:5]), 5
    while pos < len(state):
        size, kind = struct.unpack_from(">IB", state, pos)
        body = state[pos + 5 : pos + size] + (tail if kind == 6 else b"")
        out += struct.pack(">IB", 5 + len(body), kind) + body
        pos += size
    struct.pack_into(">I", out, 0, len(out))
    return bytes(out)


def test_configuration_data_of_5_25_1_decodes_with_its_reserved_int16s_as_extra_bytes() -> None:
    version_message, state = first_state("5.25.1")
    newer = with_configuration_tail(state, struct.pack(">hh", 0x1234, 0x5678))  # URCL's test values
    decoder = PrimaryStreamDecoder()
    decoded = [m for _, m in decoder.feed(version_message + newer)][1]
    assert isinstance(decoded, RobotStateMessage)
    config = next(p for p in decoded.sub_packages if p.NAME == "configuration_data")
    assert isinstance(config, PrimaryPart)
    assert config.extra == struct.pack(">hh", 0x1234, 0x5678) and not config.missing
    assert config.robot_sub_type is not None and decoder.warnings_for(decoded) == []
    assert encode_message(decoded) == newer
