"""URScript motion on the controller model: profiles, straight lines, speeds, stops, the speed
slider, power and safety states, and faults reported with their line — stepped as the server does."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rtde_spec._generated.enums import ProgramState, RobotMode, SafetyMode
from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.controller.model import HOME_Q, ControllerModel
from rtde_spec.metamodel.arms import arm_model

HZ = 500


def run(model: ControllerModel, seconds: float) -> list[dict[str, object]]:
    """Step the model for `seconds`; the outputs after every step."""
    out = []
    for _ in range(round(seconds * HZ)):
        model.tick(model.step + 1)
        out.append(dict(model.values))
    return out


def until_stopped(model: ControllerModel, limit: float = 30.0) -> list[dict[str, object]]:
    out = []
    while model.program is not None:
        model.tick(model.step + 1)
        out.append(dict(model.values))
        assert len(out) < limit * HZ, "program did not end"
    return out


def kinds(model: ControllerModel) -> list[tuple[str, str, int]]:
    return [(e.kind, e.text, e.line) for e in model.drain_events()]


def test_movej_default_profile_lasts_what_the_trapezoid_says_and_joints_arrive_together() -> None:
    model = ControllerModel("5.15.0")
    target = [q + d for q, d in zip(HOME_Q, (1.0, -0.5, 0.25, 0.0, 0.5, -0.8), strict=True)]
    model.run_script(f"movej({target})")
    steps = until_stopped(model)
    # lead joint 1.0 rad at the Script manual's defaults v=1.05 rad/s, a=1.4 rad/s^2: D/v + v/a
    assert len(steps) / HZ == pytest.approx(1.0 / 1.05 + 1.05 / 1.4, abs=0.01)
    assert model.values["actual_q"] == pytest.approx(target, abs=1e-9)
    speeds = np.array([s["actual_qd"] for s in steps])
    assert np.max(np.abs(speeds[:, 0])) == pytest.approx(1.05, abs=1e-6)  # cruises at v
    ratios = speeds[len(steps) // 2] / np.array((1.0, -0.5, 0.25, 1.0, 0.5, -0.8))
    assert ratios[[0, 1, 2, 4, 5]] == pytest.approx([ratios[0]] * 5)  # synchronised: same fraction
    assert steps[len(steps) // 2]["runtime_state"] == ProgramState.RUNNING
    assert model.values["runtime_state"] == ProgramState.STOPPED and not np.any(model.values["actual_qd"])


def test_the_speed_slider_slows_the_program_down() -> None:
    fast, slow = ControllerModel("5.15.0"), ControllerModel("5.15.0")
    slow.apply_inputs({"speed_slider_mask": 1, "speed_slider_fraction": 0.5})
    for model in (fast, slow):
        model.run_script("movej([0.5, -1.2, 1.2, -1.5, -1.5, 0.5], a=2, v=1)")
    t_fast, t_slow = len(until_stopped(fast)), len(until_stopped(slow))
    assert t_slow / t_fast == pytest.approx(2.0, rel=0.02)
    assert slow.values["actual_q"] == pytest.approx(fast.values["actual_q"])
    slow.run_script("movej([0, -1.2, 1.2, -1.5, -1.5, 0.5])")
    assert run(slow, 0.1)[-1]["speed_scaling"] == 0.5


def test_movel_keeps_the_tcp_on_the_straight_line_and_ends_at_the_pose() -> None:
    model = ControllerModel("5.15.0")
    pose = model.values["actual_TCP_pose"]
    start = np.array(pose[:3])
    goal = [pose[0] + 0.15, pose[1] - 0.1, pose[2] + 0.05, *pose[3:]]
    model.run_script(f"movel(p{goal}, a=1.2, v=0.1)")
    steps = until_stopped(model)
    direction = (np.array(goal[:3]) - start) / np.linalg.norm(np.array(goal[:3]) - start)
    for s in steps:
        p = np.array(s["actual_TCP_pose"][:3]) - start
        assert np.linalg.norm(p - direction * (p @ direction)) < 1e-6  # on the line
    speeds = [np.linalg.norm(s["actual_TCP_speed"][:3]) for s in steps]
    assert max(speeds) == pytest.approx(0.1, rel=1e-3)  # v is the tool speed
    assert model.values["actual_TCP_pose"] == pytest.approx(goal, abs=1e-6)
    assert kin.forward(arm_model("UR5e"), model.values["actual_q"]) == pytest.approx(goal, abs=1e-6)


def test_movej_to_a_pose_and_movel_to_joints_convert_with_the_arm_kinematics() -> None:
    model = ControllerModel("5.15.0", model="UR10e")
    joints = [0.2, -1.4, 1.3, -1.5, -1.6, 0.1]
    pose = list(kin.forward(arm_model("UR10e"), joints))
    model.run_script(f"movej(p{pose})\nmovel({[0.1, -1.4, 1.3, -1.5, -1.6, 0.1]})")
    until_stopped(model)
    assert model.values["actual_q"] == pytest.approx([0.1, -1.4, 1.3, -1.5, -1.6, 0.1], abs=1e-6)
    assert kinds(model)[-1][0] == "program_stopped"


def test_speedj_moves_at_the_speed_and_the_end_of_the_program_stops_it() -> None:
    model = ControllerModel("5.15.0")
    model.run_script("speedj([0.2, 0, 0, 0, 0, -0.1], a=2.0, t=0.5)")
    steps = until_stopped(model)
    assert steps[-1]["actual_qd"] == pytest.approx([0.2, 0, 0, 0, 0, -0.1])
    assert steps[-1]["actual_q"][0] - HOME_Q[0] == pytest.approx(0.2 * 0.5 - 0.2**2 / (2 * 2.0), abs=2e-3)
    run(model, 0.5)  # decelerating at a
    assert not np.any(model.values["actual_qd"])


def test_stopj_brings_a_move_to_rest_early() -> None:
    model = ControllerModel("5.15.0")
    model.run_script("speedj([0.5, 0, 0, 0, 0, 0], 5.0, 1.0)\nstopj(10)")
    steps = until_stopped(model)
    assert len(steps) / HZ == pytest.approx(1.0 + 0.05, abs=0.01)  # 0.5 rad/s at 10 rad/s^2
    assert not np.any(model.values["actual_qd"])


def test_movep_blends_through_its_waypoints() -> None:
    def duration(r: float) -> int:
        model = ControllerModel("5.15.0")
        p = model.values["actual_TCP_pose"]
        a = [p[0] + 0.1, p[1], p[2], *p[3:]]
        b = [p[0] + 0.1, p[1] + 0.1, p[2], *p[3:]]
        model.run_script(f"movep(p{a}, a=1.2, v=0.1, r={r})\nmovep(p{b}, a=1.2, v=0.1)")
        steps = len(until_stopped(model))
        assert model.values["actual_TCP_pose"] == pytest.approx(b, abs=1e-6)
        return steps

    assert duration(0.02) < duration(0.0) - 0.1 * HZ


@pytest.mark.parametrize(
    "between",
    [
        "",
        "  signal_async_progress(1)\n",  # ur_rtde's path: a function that sets a register
        '  $ 5 "Waypoint_2"\n  n = n + 1\n',  # PolyScope's label, and an assignment
    ],
)
def test_a_blended_move_blends_past_statements_that_do_not_wait(between: str) -> None:
    """The controller runs statements that cannot wait while it looks ahead to the next motion:
    a blend radius rounds the corner whatever stands between two moves. Only a move right
    after another blended; with ur_rtde's signal_async_progress(i) before each waypoint the
    arm stopped dead at every one (a square path 40 % slower)."""

    def run_path(between: str) -> tuple[int, float]:
        model = ControllerModel("5.15.0")
        p = model.values["actual_TCP_pose"]
        a = [p[0] + 0.1, p[1], p[2], *p[3:]]
        b = [p[0] + 0.1, p[1] + 0.1, p[2], *p[3:]]
        model.run_script(
            "def path():\n  n = 0\n  def signal_async_progress(i):\n    write_output_integer_register(2, i)\n"
            f"  end\n  movel(p{a}, a=1.2, v=0.25, r=0.03)\n{between}  movel(p{b}, a=1.2, v=0.25)\nend\n"
        )
        steps = until_stopped(model)
        assert model.values["actual_TCP_pose"] == pytest.approx(b, abs=1e-6)
        nearest = min(math.dist(s["actual_TCP_pose"][:3], a[:3]) for s in steps)
        return len(steps), nearest

    blended, corner = run_path(between)
    stopped, _ = run_path(between + "  sync()\n")  # a wait: no blend
    assert corner > 0.02  # the corner was cut by about the radius
    assert blended < stopped - 0.1 * HZ


def test_power_brakes_and_protective_stop_gate_motion() -> None:
    model = ControllerModel("5.15.0")
    model.power_off()
    assert model.values["robot_mode"] == RobotMode.POWER_OFF
    assert model.run_script("movej([0, -1.57, 1.57, -1.57, -1.57, 0])") is None
    assert kinds(model)[0][0] == "runtime_exception"
    assert not model.release_brakes()  # not while powered off
    assert model.power_on() and model.values["robot_mode"] == RobotMode.IDLE
    assert model.release_brakes() and model.values["robot_mode"] == RobotMode.RUNNING
    model.run_script("movej([0.5, -1.57, 1.57, -1.57, -1.57, 0], a=1, v=0.5)")
    run(model, 0.3)
    assert model.protective_stop()
    frozen = model.values["actual_q"]
    after = run(model, 0.5)
    assert after[-1]["actual_q"] == frozen and after[-1]["speed_scaling"] == 0.0
    assert model.values["safety_mode"] == SafetyMode.PROTECTIVE_STOP
    assert model.values["runtime_state"] == ProgramState.PAUSED
    assert not model.play()  # still stopped
    assert model.unlock_protective_stop() and model.play()
    until_stopped(model)
    assert model.values["actual_q"][0] == pytest.approx(0.5)
    model.run_script("movej([0, -1.57, 1.57, -1.57, -1.57, 0], a=1, v=0.5)")
    run(model, 0.2)
    assert model.stop_program() and model.values["runtime_state"] == ProgramState.STOPPED
    run(model, 1.0)
    assert not np.any(model.values["actual_qd"])


@pytest.mark.parametrize(
    ("script", "text", "line"),
    [
        ('def prog():\n  textmsg("a")\n  movej([0, 0, 0])\nend', "movej: q must be six numbers", 3),
        ("def prog():\n  x = 1\n  fly_to(x)\nend", "compile_error_name_not_found:fly_to:", 3),
        ("def prog():\n  movej([0, -1.57, 1.57, -1.57, -1.57, 0], v=fast)\nend", "name_not_found:fast", 2),
        ("movej([0, -1.57, 7.0, -1.57, -1.57, 0])", "outside the UR5e's range", 1),
        ("def prog():\n  x = 1\n  t = run mover()\nend", "compile_error_name_not_found:mover:", 3),
        ("movej([0, 0, 0, 0, 0, 0]", "syntax_error_on_line:1:", 1),
        ("set_standard_digital_out(9, True)", "no output 9", 1),
    ],
)
def test_what_cannot_run_is_a_runtime_exception_with_its_line(script: str, text: str, line: int) -> None:
    model = ControllerModel("5.15.0")
    model.run_script(script)
    run(model, 0.05)
    faults = [e for e in model.drain_events() if e.kind == "runtime_exception"]
    assert len(faults) == 1 and text in faults[0].text and faults[0].line == line
    assert model.program is None and model.values["runtime_state"] == ProgramState.STOPPED


def test_a_movel_out_of_reach_goes_along_its_line_and_stops_where_the_line_leaves_reach() -> None:
    """It was refused before moving; a controller starts it (PolyScope's Direction node moves
    towards a point 1000 m away) and stops where the arm cannot follow the line: a protective stop,
    the program paused (URCL's tests against URSim wait for one: test_instruction_executor.cpp:317)."""
    model = ControllerModel("5.15.0")
    start = list(model.values["actual_TCP_pose"])
    model.run_script(
        f"movel(p[{start[0]}, {start[1]}, {start[2] + 5}, {start[3]}, {start[4]}, {start[5]}], v=0.5)"
    )
    run(model, 0.2)
    assert model.program is not None  # moving, no error yet
    assert model.values["actual_TCP_pose"][2] > start[2] + 0.01
    for _ in range(30 * HZ):
        if model.values["safety_mode"] == SafetyMode.PROTECTIVE_STOP:
            break
        model.tick(model.step + 1)
    assert model.values["safety_mode"] == SafetyMode.PROTECTIVE_STOP
    assert model.program is not None and model.values["runtime_state"] == ProgramState.PAUSED
    assert not [e for e in model.drain_events() if e.kind == "runtime_exception"]
    assert start[2] + 0.1 < model.values["actual_TCP_pose"][2] < start[2] + 1.5  # the edge of its reach


def test_a_direction_node_moves_towards_a_far_point_until_its_thread_is_killed() -> None:
    model = ControllerModel("5.15.0")
    start = list(model.values["actual_TCP_pose"])
    model.run_script(
        "def prog():\n"
        "  thread mover():\n"
        "    movel(pose_add(get_target_tcp_pose(), p[0, 0, -1000.0, 0, 0, 0]), a=1.2, v=0.05)\n"
        "  end\n"
        "  h = run mover()\n"
        "  sleep(0.4)\n"
        "  kill h\n"
        "  stopl(3.0)\n"
        "end"
    )
    until_stopped(model)
    assert not [e for e in model.drain_events() if e.kind == "runtime_exception"]
    assert start[2] - 0.03 < model.values["actual_TCP_pose"][2] < start[2] - 0.005  # ~0.05 m/s for 0.4 s


def test_io_payload_tcp_and_messages() -> None:
    model = ControllerModel("5.15.0")
    model.run_script(
        "def prog():\n"
        "  set_digital_out(1, True)\n"
        "  set_tool_digital_out(1, True)\n"
        "  set_analog_out(0, 0.3)\n"
        "  set_payload(1.5, [0, 0, 0.05])\n"
        "  set_tcp(p[0, 0, 0.1, 0, 0, 0])\n"
        '  textmsg("at ", 3)\n'
        '  popup("check", "Title", warning=True)\n'
        "  sleep(0.1)\n"
        "end"
    )
    until_stopped(model)
    values = model.values
    assert values["actual_digital_output_bits"] == (1 << 1) | (1 << 17)
    assert values["standard_analog_output0"] == pytest.approx(0.3)
    assert values["payload"] == 1.5 and values["payload_cog"] == (0.0, 0.0, 0.05)
    assert values["tcp_offset"] == (0.0, 0.0, 0.1, 0.0, 0.0, 0.0)
    flange = kin.forward(arm_model("UR5e"), values["actual_q"])
    assert values["actual_TCP_pose"][2] == pytest.approx(flange[2] - 0.1)  # the tool points down at home
    events = model.drain_events()
    said = [(e.kind, e.text) for e in events if e.kind in ("text", "popup")]
    assert said == [("text", "at 3"), ("popup", "check")]
    assert events[0].kind == "program_started" and events[0].text == "prog"


def test_a_new_program_replaces_the_running_one() -> None:
    model = ControllerModel("5.15.0")
    model.run_script("movej([1.0, -1.57, 1.57, -1.57, -1.57, 0], a=1, v=0.3)")
    run(model, 0.5)
    model.run_script(f"movej({list(HOME_Q)}, a=1, v=0.3)")
    until_stopped(model)
    assert model.values["actual_q"][0] == pytest.approx(0.0)
    assert math.isclose(model.values["actual_TCP_pose"][0], kin.forward(arm_model("UR5e"), HOME_Q)[0])


def test_a_servoj_stream_reports_the_speed_it_moves_at_and_rests_when_it_ends() -> None:
    """ur_rtde's servoJ loop: one servoj(t=0.002) a control step, each reached within its step.
    actual_qd and the TCP speed were 0 all through the stream, as if the arm stood still."""
    model = ControllerModel("5.15.0")
    rate = -0.2  # rad/s on the base joint
    targets = [[q + (rate * (i + 1) / HZ if j == 0 else 0) for j, q in enumerate(HOME_Q)] for i in range(100)]
    lines = [f"servoj({q}, t=0.002)" for q in targets]
    model.run_script("def stream():\n  " + "\n  ".join(lines) + "\n  sync()\n  sync()\nend\n")
    steps = until_stopped(model)
    moving = [s for s in steps if s["actual_q"][0] != steps[-1]["actual_q"][0]]
    assert len(moving) >= 90
    speeds = [s["actual_qd"][0] for s in moving]
    assert all(qd == pytest.approx(rate) for qd in speeds[5:]), speeds
    assert max(abs(s["actual_TCP_speed"][1]) + abs(s["actual_TCP_speed"][0]) for s in moving) > 0.01
    assert model.values["actual_q"][0] == pytest.approx(HOME_Q[0] + rate * 100 / HZ, abs=1e-3)
    assert not np.any(model.values["actual_qd"])  # the stream ended: at rest
