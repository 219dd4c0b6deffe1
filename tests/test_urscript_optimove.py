"""optimovej / optimovel, which the ROS driver's external control program (UR's client library)
calls on e-Series 5.21+ and PolyScope X 10.8+: before, the emulator refused that program at
compile time (`compile_error_name_not_found:optimovej`) and the driver never started."""

from __future__ import annotations

import math

import pytest

from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.controller.model import ControllerModel

HZ = 500


def run(script: str, version: str, seconds: float = 20.0) -> tuple[ControllerModel, list[tuple[str, str]]]:
    model = ControllerModel(version)
    model.run_script(script)
    for _ in range(int(seconds * HZ)):
        if model.program is None:
            break
        model.tick(model.step + 1)
    return model, [(e.kind, e.text) for e in model.drain_events()]


def test_optimovej_and_optimovel_end_at_their_targets_at_fractions_of_the_limits() -> None:
    target = [0.3, -1.2, 1.4, -1.8, -1.5, 0.2]
    script = (
        "def prog():\n"
        f"  optimovej({target}, a=0.4, v=0.7)\n"
        '  textmsg("joints")\n'
        "  optimovel(pose_add(get_actual_tcp_pose(), p[0.0, 0.05, -0.05, 0, 0, 0]), 0.4, 0.7)\n"
        '  textmsg("tool")\n'
        "end"
    )
    model, events = run(script, "5.21.0")
    assert [text for kind, text in events if kind == "text"] == ["joints", "tool"]
    assert not [e for e in events if e[0] == "runtime_exception"]
    arm = model.arm
    expected = kin.forward(arm.model, target, arm.tcp)
    got = kin.forward(arm.model, list(arm.state.q), arm.tcp)
    assert got[:3] == pytest.approx([expected[0], expected[1] + 0.05, expected[2] - 0.05], abs=1e-4)


def test_optimovej_takes_as_long_as_its_speed_fraction_says() -> None:
    """v=0.5 of 180 deg/s: a 1 rad move takes about 1 / (pi / 2) s plus its ramps."""
    model = ControllerModel("5.25.1")
    start = [float(v) for v in model.arm.state.q]
    goal = [start[0] + 1.0, *start[1:]]
    model.run_script(f"def prog():\n  optimovej({goal}, a=1.0, v=0.5)\nend")
    steps = 0
    while model.program is not None and steps < 10 * HZ:
        model.tick(model.step + 1)
        steps += 1
    seconds = steps / HZ
    cruise = 1.0 / (math.radians(180.0) * 0.5)
    assert cruise < seconds < cruise + 0.5
    assert model.arm.state.q[0] == pytest.approx(goal[0], abs=1e-6)


@pytest.mark.parametrize(("version", "known"), [("5.20.0", False), ("5.21.0", True), ("10.8.0", True)])
def test_optimove_is_known_from_5_21_on(version: str, known: bool) -> None:
    script = (
        'def prog():\n  if False:\n    optimovej(get_actual_joint_positions())\n  end\n  textmsg("ok")\nend'
    )
    _, events = run(script, version, seconds=1)
    assert (("text", "ok") in events) == known
    if not known:
        assert any("optimovej" in text for kind, text in events if kind == "runtime_exception")


@pytest.mark.parametrize("fraction", ["0", "1.5", "-0.2"])
def test_a_fraction_outside_0_to_1_is_a_runtime_exception(fraction: str) -> None:
    _, events = run(f"def prog():\n  optimovej(get_actual_joint_positions(), a={fraction})\nend", "5.21.0")
    assert any("fraction in (0, 1]" in text for kind, text in events if kind == "runtime_exception")
