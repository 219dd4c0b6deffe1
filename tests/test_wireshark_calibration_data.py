"""The generated dissector shows Calibration Data field by field (Fx..Frz, the 5.9/5.10
interface document's layout), agreeing with our capture tables value by value."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rtde_spec.capture.decoder import capture_tables

from .test_primary_calibration_data import BODY, FIELDS, VALUES, calibration_capture
from .test_wireshark import tshark  # skips this module where tshark is missing, as there


def test_dissector_shows_each_calibration_field(tmp_path: Path) -> None:
    second = struct.pack(">6d", *(v * 10 for v in VALUES))
    path = calibration_capture(tmp_path, [BODY, second])
    rows = tshark(path, "urprimary.calibration_data.fx", *(f"urprimary.calibration_data.{f}" for f in FIELDS))
    ours = capture_tables(path)["primary_calibration_data"].to_pylist()
    assert len(rows) == len(ours) == 2
    for row, mine in zip(rows, ours, strict=True):
        assert [float(x) for x in row] == pytest.approx([mine[f] for f in FIELDS])
    assert [float(x) for x in rows[1]] == pytest.approx([v * 10 for v in VALUES])
