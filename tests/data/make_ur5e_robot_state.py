"""How tests/data/ur5e_robot_state.hex was made: a Robot State shaped like a UR5e's
(13 sub-packages in the order an e-Series controller sends them, about 1.4 kB), from
the sub-packages hand-packed with struct in make_primary_golden.py (typed from the
document, independent of the spec and the codec). The benchmark and tests read the hex.

    python tests/data/make_ur5e_robot_state.py > tests/data/ur5e_robot_state.hex
"""

from __future__ import annotations

import struct
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from make_primary_golden import CASES

# sub-package type numbers from the document, in a UR5e's order
UR5E_ORDER = [
    ("robot_mode_data", 0),
    ("joint_data", 1),
    ("cartesian_info", 4),
    ("kinematics_info", 5),
    ("configuration_data", 6),
    ("masterboard_data", 3),
    ("tool_data", 2),
    ("force_mode_data", 7),
    ("additional_info", 8),
    ("safety_data", 10),
    ("tool_comm_info", 11),
    ("tool_mode_info", 12),
    ("cumulative_runtime_data", 16),
]


def main() -> None:
    by_name = {}
    for name, data, *_ in CASES:
        by_name.setdefault(name, data)
    subs = []
    for name, number in UR5E_ORDER:
        whole = by_name[name]
        body = whole[5:]  # the golden case is a Robot State holding exactly this sub-package
        sub_size, sub_type = struct.unpack_from(">IB", body)
        assert sub_type == number and sub_size == len(body), name
        subs.append(body)
    payload = b"".join(subs)
    message = struct.pack(">IB", 5 + len(payload), 16) + payload
    print("# UR5e-like Robot State, 13 sub-packages; made by tests/data/make_ur5e_robot_state.py")
    print(message.hex())


if __name__ == "__main__":
    main()
