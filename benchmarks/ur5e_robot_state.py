"""The UR5e-like Robot State of the benchmark: 13 sub-packages, about 1.3 kB; and a stream of
distinct messages of that shape, as a moving robot sends them.

The message is packed with struct from the document's formats by
tests/data/make_ur5e_robot_state.py, independent of the spec and the codec; the benchmark
and the tests read the same bytes.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path

HEX = Path(__file__).resolve().parent.parent / "tests" / "data" / "ur5e_robot_state.hex"

# Sub-packages whose values change in every message of a moving robot, and the fields that do;
# the others (kinematics, configuration, additional info, safety, tool communication and
# tool mode) keep their bytes, as on a real robot.
MOVING = {
    "robot_mode_data": ("timestamp",),
    "joint_data": ("q_actual", "q_target", "qd_actual", "i_actual", "v_actual", "t_motor", "reserved"),
    "cartesian_info": (
        *("x", "y", "z", "rx", "ry", "rz"),
        *("tcp_offset_x", "tcp_offset_y", "tcp_offset_z", "tcp_offset_rx", "tcp_offset_ry", "tcp_offset_rz"),
    ),
    "masterboard_data": (
        *("analog_input0", "analog_input1", "analog_output0", "analog_output1"),
        *("masterboard_temperature", "robot_voltage_48v", "robot_current", "master_io_current"),
    ),
    "tool_data": ("analog_input0", "analog_input1", "tool_voltage_48v", "tool_current", "tool_temperature"),
    "force_mode_data": ("fx", "fy", "fz", "frx", "fry", "frz", "robot_dexterity"),
    "cumulative_runtime_data": ("robot_energy_consumed_wh", "robot_braking_energy_dissipated_wh"),
}


def ur5e_robot_state_bytes() -> bytes:
    lines = [line for line in HEX.read_text().splitlines() if line and not line.startswith("#")]
    return bytes.fromhex("".join(lines))


def _wave(i: int, k: int) -> float:
    """A value that moves a little every message (no two messages alike, no round numbers)."""
    return 1.0 + 0.5 * math.sin(0.0137 * i + 0.71 * k) + 1e-7 * i


def moving_robot_stream(count: int = 1000) -> list[bytes]:
    """`count` distinct Robot State messages of the benchmark message's shape: in every one,
    every sub-package of MOVING has new values (timestamp +100 ms, joints, pose, currents,
    voltages, temperatures, analog values, forces, energy), the rest its bytes unchanged.

    Built through the models and encode_message; checked here at the byte level.
    """
    from rtde_spec.primary.codec import decode_message, encode_message
    from rtde_spec.wire.primary_base import RobotStateMessage

    base = decode_message(ur5e_robot_state_bytes())
    assert isinstance(base, RobotStateMessage)
    out = []
    for i in range(count):
        subs = []
        for part in base.sub_packages:
            names = MOVING.get(part.NAME)
            if names is None:
                subs.append(part)
            elif part.NAME == "joint_data":
                joints = [
                    j.model_copy(update={n: _wave(i, 10 * k + f) for f, n in enumerate(names)})
                    for k, j in enumerate(part.joints)
                ]
                subs.append(part.model_copy(update={"joints": tuple(joints)}))
            elif part.NAME == "robot_mode_data":
                subs.append(part.model_copy(update={"timestamp": part.timestamp + 100_000 * i}))
            else:
                subs.append(part.model_copy(update={n: _wave(i, f) for f, n in enumerate(names)}))
        out.append(encode_message(RobotStateMessage(sub_packages=subs)))
    _check(out, [p.NAME for p in base.sub_packages])
    return out


def _sub_packages(message: bytes) -> list[bytes]:
    pos, subs = 5, []
    while pos < len(message):
        size = struct.unpack_from(">I", message, pos)[0]
        subs.append(message[pos : pos + size])
        pos += size
    return subs


def _check(stream: list[bytes], names: list[str]) -> None:
    """Every moving sub-package differs from the message before's (the last's, for the first:
    a benchmark goes round), every other is equal."""
    assert len(stream) > 1, "a stream of one message repeats it"
    before = _sub_packages(stream[-1])
    for message in stream:
        subs = _sub_packages(message)
        for name, a, b in zip(names, before, subs, strict=True):
            assert len(a) == len(b) and (a != b) == (name in MOVING), name
        before = subs
