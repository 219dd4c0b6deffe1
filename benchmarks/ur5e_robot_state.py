"""The UR5e-like Robot State of the benchmark: 13 sub-packages, about 1.3 kB.

Packed with struct from the document's formats by tests/data/make_ur5e_robot_state.py,
independent of the spec and the codec; the benchmark and the tests read the same bytes.
"""

from __future__ import annotations

from pathlib import Path

HEX = Path(__file__).resolve().parent.parent / "tests" / "data" / "ur5e_robot_state.hex"


def ur5e_robot_state_bytes() -> bytes:
    lines = [line for line in HEX.read_text().splitlines() if line and not line.startswith("#")]
    return bytes.fromhex("".join(lines))
