"""Arm kinematics against poses worked out another way: by hand from the DH table, and by an
explicit chain of rotation matrices and translations built here, from the YAML file itself."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.errors import SpecError, UsageError
from rtde_spec.metamodel.arms import arm_model, arm_models, load_arms
from tests.budget import examples

from .helpers import ROOT

ARMS_YAML = yaml.safe_load((ROOT / "spec" / "arms" / "models.yaml").read_text())["models"]
NAMES = [m["name"] for m in ARMS_YAML]
angles = st.floats(-math.pi, math.pi, allow_nan=False)
joints = st.tuples(angles, angles, angles, angles, angles, angles)
offsets = st.tuples(*(st.floats(-0.15, 0.15) for _ in range(3)), *(st.floats(-1.0, 1.0) for _ in range(3)))


def rot_z(t: float) -> np.ndarray:
    return np.array([[math.cos(t), -math.sin(t), 0], [math.sin(t), math.cos(t), 0], [0, 0, 1]])


def rot_x(t: float) -> np.ndarray:
    return np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]])


def chain(name: str, q: tuple[float, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Flange rotation and position: for each joint turn about z, go d along z, a along x, turn about x."""
    row = next(m for m in ARMS_YAML if m["name"] == name)["dh"]
    rot, pos = np.eye(3), np.zeros(3)
    for i in range(6):
        rot = rot @ rot_z(q[i])
        pos = pos + rot @ np.array([0.0, 0.0, row["d"][i]])
        pos = pos + rot @ np.array([row["a"][i], 0.0, 0.0])
        rot = rot @ rot_x(row["alpha"][i])
    return rot, pos


def rotation_of(pose: tuple[float, ...]) -> np.ndarray:
    """Rodrigues written out with the axis-angle formula's matrix exponential (scipy-free, numpy)."""
    v = np.array(pose[3:6])
    angle = np.linalg.norm(v)
    if angle < 1e-12:
        return np.eye(3)
    k = v / angle
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def test_ur5e_at_zero_joints_by_hand() -> None:
    # all joints 0: the arm lies along -x (a2 + a3), the wrist offsets d4 and d6 go along -y,
    # d5 down; the flange faces -y: a quarter turn about x
    pose = kin.forward(arm_model("UR5e"), (0.0,) * 6)
    expected = (-0.425 - 0.3922, -(0.1333 + 0.0996), 0.1625 - 0.0997, math.pi / 2, 0, 0)
    assert pose == pytest.approx(expected, abs=1e-12)


def test_ur5e_upright_by_hand() -> None:
    # shoulder and wrist 1 at -90 degrees: the arm stands straight up, the flange faces -y
    pose = kin.forward(arm_model("UR5e"), (0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0))
    assert pose[:3] == pytest.approx((0.0, -(0.1333 + 0.0996), 0.1625 + 0.425 + 0.3922 + 0.0997), abs=1e-12)
    assert rotation_of(pose) @ np.array([0, 0, 1.0]) == pytest.approx([0, -1, 0], abs=1e-12)


def test_home_of_the_emulator_faces_down() -> None:
    # the emulator's start pose (0, -90, 90, -90, -90, 0 deg) holds the tool pointing at the floor
    model = ControllerModel("5.15.0")
    pose = model.values["actual_TCP_pose"]
    assert rotation_of(pose) @ np.array([0, 0, 1.0]) == pytest.approx([0, 0, -1], abs=1e-4)
    assert pose == pytest.approx(kin.forward(arm_model("UR5e"), model.values["actual_q"]))


@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=examples(60), deadline=None)
@given(q=joints)
def test_forward_matches_an_explicit_chain(name: str, q: tuple[float, ...]) -> None:
    rot, pos = chain(name, q)
    pose = kin.forward(arm_model(name), q)
    assert pose[:3] == pytest.approx(tuple(pos), abs=1e-9)
    assert rotation_of(pose) == pytest.approx(rot, abs=1e-9)
    assert math.sqrt(sum(v * v for v in pose[3:])) <= math.pi + 1e-12  # UR's rotation vectors


@pytest.mark.parametrize("name", ["UR5e", "UR3", "UR10e", "UR16e", "UR30"])
@settings(max_examples=examples(150), deadline=None)
@given(q=joints, tcp=offsets)
def test_every_inverse_solution_reaches_the_pose_and_the_nearest_is_where_we_were(
    name: str, q: tuple[float, ...], tcp: tuple[float, ...]
) -> None:
    arm = arm_model(name)
    pose = kin.forward(arm, q, tcp)
    solutions = kin.inverse_all(arm, pose, tcp, q6=q[5])  # q6: where wrist 3 is free (sin q5 = 0)
    assert 1 <= len(solutions) <= 8
    target = kin.pose_to_matrix(pose)
    # at a singularity (wrist: sin q5 = 0; arm stretched: sin q3 = 0) precision is lost, as on any arm
    regular = abs(math.sin(q[4])) > 1e-3 and abs(math.sin(q[2])) > 1e-3
    for sol in solutions:
        reached = kin.pose_to_matrix(kin.forward(arm, sol, tcp))
        assert reached == pytest.approx(target, abs=1e-7 if regular else 1e-4)
    if regular:  # away from singularities the answer is unique
        assert kin.nearest(arm, pose, q, tcp) == pytest.approx(q, abs=1e-6)
        assert kin.nearest(arm, pose, q, tcp, same_branch=True) == pytest.approx(q, abs=1e-6)


def test_a_generic_pose_has_eight_distinct_solutions() -> None:
    arm = arm_model("UR5e")
    pose = kin.forward(arm, (0.3, -1.5, 2.0, -1.2, 1.0, 0.4))  # near the base: every branch reaches
    solutions = kin.inverse_all(arm, pose)
    assert len({tuple(np.round(s, 6)) for s in solutions}) == 8


def test_out_of_reach_is_refused() -> None:
    with pytest.raises(UsageError, match="out of reach of the UR5e"):
        kin.nearest(arm_model("UR5e"), (2.0, 0.0, 0.5, 0.0, math.pi, 0.0), (0.0,) * 6)


@pytest.mark.parametrize("angle", [0.0, 1e-9, 0.5, math.pi / 2, math.pi - 1e-7, math.pi])
def test_rotation_vectors_round_trip(angle: float) -> None:
    axis = np.array([0.3, -0.5, 0.81])
    axis /= np.linalg.norm(axis)
    rv = tuple(axis * angle)
    back = kin.matrix_to_rotvec(kin.rotvec_to_matrix(rv))
    assert rotation_of((0, 0, 0, *back)) == pytest.approx(rotation_of((0, 0, 0, *rv)), abs=1e-9)


def test_the_generated_table_is_the_yaml() -> None:
    assert [m.name for m in arm_models().values()] == NAMES
    for row in ARMS_YAML:
        arm = arm_model(row["name"].lower())
        assert list(arm.dh.a) == row["dh"]["a"] and list(arm.dh.d) == row["dh"]["d"]
        assert arm.payload_kg == row["payload_kg"]


def test_unknown_model_names_the_known_ones() -> None:
    with pytest.raises(UsageError, match="known: UR3, UR5"):
        arm_model("UR99")


def test_a_bad_arms_file_is_refused_with_its_line(tmp_path: Path) -> None:
    good = (ROOT / "spec" / "arms" / "models.yaml").read_text()
    (tmp_path / "arms").mkdir()
    bad = good.replace("    reach_m: 0.85\n", "    reach_m: 0.85\n    colour: blue\n", 1)
    bad = bad.replace("d: [0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819]", "d: [0.1519, 0.0]")
    (tmp_path / "arms" / "models.yaml").write_text(bad)
    with pytest.raises(SpecError) as caught:
        load_arms(tmp_path)
    text = str(caught.value)
    assert "unknown key 'colour'" in text and "models[0](UR3).dh.d" in text and "arms/models.yaml:" in text
    (tmp_path / "arms" / "models.yaml").write_text(good + good[good.index("  - name: UR30") :])
    with pytest.raises(SpecError, match="given twice"):
        load_arms(tmp_path)


def test_a_scenario_that_sets_the_joints_gets_the_pose_of_those_joints() -> None:
    q = (0.5, -1.0, 1.5, -0.5, 0.25, 2.0)
    model = ControllerModel("5.15.0", functions={"actual_q": lambda t: q}, model="UR10e")
    model.tick(10)
    assert model.values["actual_q"] == q
    assert model.values["actual_TCP_pose"] == pytest.approx(kin.forward(arm_model("UR10e"), q))
    _, pos = chain("UR10e", q)
    assert model.values["actual_TCP_pose"][:3] == pytest.approx(tuple(pos))
