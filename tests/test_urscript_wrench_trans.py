"""wrench_trans(T_from_to, w_from): F' = R F, M' = R M + p x F' for T = (R, p). The manual's one
line ("w_to = T_from->to * w_from") leaves the direction open; UR's impedance and admittance
examples, which ran on arms, fix it: a velocity put through it (angular and linear swapped, their
screw_trans / adm_vel_trans) comes out as rigid-body motion says it must."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtde_spec.emulator.arm import kinematics as kin

from .test_urscript_control import faults, run, said

# UR's URScript_Examples admittance-control/admittance_control.script (nested in the program)
ADM_VEL_TRANS = (
    "  def adm_vel_trans(t, v):\n"
    "    local vw = wrench_trans(t, [v[3], v[4], v[5], v[0], v[1], v[2]])\n"
    "    return [vw[3], vw[4], vw[5], vw[0], vw[1], vw[2]]\n"
    "  end\n"
)


def values(script: str) -> list[list[float]]:
    _, events = run(script)
    assert not faults(events)
    return [[float(x) for x in text.strip("[]").split(",")] for text in said(events)]


def test_a_force_at_an_offset_frame_gives_its_moment_and_turns_with_the_frame() -> None:
    got = values(
        "def prog():\n"
        "  textmsg(wrench_trans(p[0, 0, 0.1, 0, 0, 0], [1, 0, 0, 0, 0, 0]))\n"
        "  textmsg(wrench_trans(p[0, 0, 0, 0, 0, 1.5707963267948966], [1, 0, 0, 0, 0, 2]))\n"
        "end\n"
    )
    assert got[0] == pytest.approx([1, 0, 0, 0, 0.1, 0])
    assert got[1] == pytest.approx([0, 1, 0, 0, 0, 2], abs=1e-6)


def test_the_admittance_example_moves_a_flange_velocity_to_the_tcp_as_rigid_motion_does() -> None:
    """The example's vel_target_tcp = adm_vel_trans(pose_inv(T_compliance_center_to_tcp), v):
    with the compliance centre at the flange, T is the TCP offset. A TCP's velocity, in TCP
    coordinates, is R^T (v + w x p) for the flange's (v, w) and the offset (R, p)."""
    offset = [0.02, -0.01, 0.15, 0.3, -0.2, 0.5]
    flange = [0.01, 0.02, -0.03, 0.4, -0.1, 0.2]
    pose = "p[" + ", ".join(map(str, offset)) + "]"
    (got,) = values(
        f"def prog():\n{ADM_VEL_TRANS}  textmsg(adm_vel_trans(pose_inv({pose}), {flange}))\nend\n"
    )
    m = kin.pose_to_matrix(offset)
    r, p = m[:3, :3], m[:3, 3]
    v, w = np.array(flange[:3]), np.array(flange[3:])
    expected = [*(r.T @ (v + np.cross(w, p))), *(r.T @ w)]
    assert got == pytest.approx(expected, abs=2e-6)  # to_str shows 6 decimals


def test_a_pose_and_its_inverse_undo_each_other() -> None:
    (got,) = values(
        "def prog():\n"
        "  t = p[0.1, 0.2, -0.3, 0.5, 1.0, -0.4]\n"
        "  textmsg(wrench_trans(pose_inv(t), wrench_trans(t, [1, -2, 3, 0.5, 0.25, -1])))\n"
        "end\n"
    )
    assert got == pytest.approx([1, -2, 3, 0.5, 0.25, -1], abs=1e-5)
    assert math.isfinite(sum(got))


@pytest.mark.parametrize(
    ("call", "problem"),
    [
        ("wrench_trans(p[0, 0, 0, 0, 0, 0], [1, 2, 3])", "w_from must be six numbers"),
        ('wrench_trans("base", [1, 2, 3, 4, 5, 6])', "pose must be six numbers"),
        ("wrench_trans(p[0, 0, 0, 0, 0, 0])", "missing argument w_from"),
    ],
)
def test_what_is_not_a_pose_and_a_wrench_is_a_runtime_exception_at_its_line(call: str, problem: str) -> None:
    _, events = run(f"def prog():\n  x = 1\n  w = {call}\nend\n")
    ((text, line, _),) = faults(events)
    assert text.startswith("wrench_trans: ") and problem in text and line == 3
