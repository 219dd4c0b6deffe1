"""The Wireshark dissector reads protocol-1 data packages with and without a recipe id (issue 27, item 6)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec import build

from .capture_files import Conversation, write
from .test_rtde_recipe_id_forms import NAMES, TYPES, with_id, without_id
from .test_wireshark import tshark  # skips this module where tshark is missing, as there


def test_dissector_reads_both_forms_in_protocol_1(tmp_path: Path) -> None:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("client", build("setup_outputs_v1", variable_names=NAMES))
    conv.send("server", build("setup_outputs_v1_reply", variable_types=TYPES))
    conv.send("client", build("start"))
    conv.send("server", build("start_reply", accepted=True))
    for i in range(12):
        conv.send("server", without_id(i) if i % 2 else with_id(i))
    conv.send("server", without_id(12) + without_id(13))  # two in one segment
    path = write(tmp_path / "v1.pcapng", [conv], "pcapng")
    rows = tshark(path, "rtde.type == 85", "rtde.timestamp", "rtde.robot_mode", "rtde.recipe_id")
    stamps = [float(t) for row in rows for t in row[0].split(",")]
    assert [round(t / 0.008) for t in stamps] == list(range(14))
    assert all(set(row[1].split(",")) == {"7"} for row in rows)
    recipe_ids = [row[2] for row in rows]  # only the packages that carry the id show one
    assert recipe_ids[:2] == ["1", ""] and recipe_ids[-1] == ""
    assert stamps[13] == pytest.approx(13 * 0.008)
