"""The built-ins of the arm's model a 5.23 controller has (spec/urscript/functions.yaml): a program
gets the emulator's jacobian, mass matrix, Coriolis torques and target accelerations, refused on a
controller older than the function; `direct_torque` takes a control step and holds the arm (the
emulator models no dynamics), the Robot Mode Data showing control mode TORQUE while it is called."""

from __future__ import annotations

import numpy as np
import pytest

from rtde_spec.emulator.arm import dynamics, jacobian
from rtde_spec.emulator.controller.model import HOME_Q, ControllerModel
from rtde_spec.emulator.urscript.builtins_modes import control_mode

TORQUE = 3  # the Robot Mode Data's control mode


def run(
    script: str, version: str = "5.23.0", steps: int = 1000
) -> tuple[ControllerModel, list[tuple[str, str]]]:
    model = ControllerModel(version)
    model.run_script(script)
    for _ in range(steps):
        if model.program is None:
            break
        model.tick(model.step + 1)
    return model, [(e.kind, e.text) for e in model.drain_events()]


def numbers(events: list[tuple[str, str]]) -> list[float]:
    return [float(text) for kind, text in events if kind == "text"]


def test_get_jacobian_is_the_arms_at_its_joints_and_at_the_joints_given() -> None:
    q2 = [0.3, -1.2, 1.1, -0.7, -1.4, 0.5]
    tcp = [0.0, 0.0, 0.1, 0.0, 0.0, 0.0]
    cells = [f"textmsg(j[{i}, {k}])" for k in range(6) for i in range(6)]
    script = (
        "j = get_jacobian()\n" + "\n".join(cells) + f"\nj = get_jacobian({q2}, p{tcp})\n" + "\n".join(cells)
    )
    model, events = run(script)
    got = numbers(events)
    assert got[:36] == pytest.approx(jacobian.jacobian(model.arm.model, HOME_Q).flatten(order="F"), abs=1e-5)
    assert got[36:] == pytest.approx(jacobian.jacobian(model.arm.model, q2, tcp).flatten(order="F"), abs=1e-5)


def test_the_model_functions_return_their_shapes() -> None:
    _, events = run(
        "textmsg(get_list_length(get_mass_matrix()))\ntextmsg(get_list_length(get_mass_matrix()[0]))\n"
        "textmsg(get_list_length(get_coriolis_and_centrifugal_torques()))\n"
        "textmsg(get_list_length(get_target_joint_accelerations()))\n"
        "textmsg(get_jacobian_time_derivative()[5, 5])\n"
        "textmsg(get_mass_matrix(include_rotors_inertia=True)[0, 0] - get_mass_matrix()[0, 0])\n"
    )
    assert numbers(events) == pytest.approx([6, 6, 6, 6, 0.0, dynamics.ROTOR_INERTIA[0]], abs=1e-5)


def test_the_mass_matrix_takes_the_payload_the_program_set() -> None:
    model, events = run("set_target_payload(4.0, [0, 0, 0.05])\ntextmsg(get_mass_matrix()[0, 0])\n")
    expected = dynamics.mass_matrix(model.arm.model, HOME_Q, 4.0, [0, 0, 0.05])[0, 0]
    assert numbers(events) == pytest.approx([expected], abs=1e-5)


def test_target_accelerations_are_the_motions_and_zero_when_still() -> None:
    _, events = run(
        "textmsg(norm(get_target_joint_accelerations()))\n"
        "def go():\n  q = get_actual_joint_positions()\n  q[0] = q[0] + 1\n  movej(q, a=0.5, v=1)\nend\n"
        "thread t():\n  go()\nend\nh = run t()\nsleep(0.1)\ntextmsg(get_target_joint_accelerations()[0])\n"
        "kill h\n"
    )
    assert numbers(events) == pytest.approx([0.0, 0.5], abs=1e-9)


@pytest.mark.parametrize(
    "call",
    ["get_jacobian()", "get_mass_matrix()", "get_jacobian_time_derivative()",
     "get_coriolis_and_centrifugal_torques()", "get_target_joint_accelerations()",
     "direct_torque([0,0,0,0,0,0])"],
)  # fmt: skip
def test_5_23_has_them_and_a_controller_before_it_lacks_them(call: str) -> None:
    name = call.split("(")[0]
    refused = ("runtime_exception", f"compile_error_name_not_found:{name}:")
    assert refused in run(f"x = 1\n{call}\n", version="5.22.0")[1]
    _, events = run(f"x = 1\n{call}\n", version="5.23.0")
    assert not [e for e in events if e[0] == "runtime_exception"], events


def test_direct_torque_takes_a_control_step_holds_the_arm_and_shows_torque_control() -> None:
    model = ControllerModel("5.26.0")
    model.run_script(
        "i = 0\nwhile i < 100:\n"
        "  direct_torque([0, 0, 0, 0, 0, 0.5], viscous_scale=[0.9, 0.9, 0.8, 0.9, 0.9, 0.9])\n"
        "  i = i + 1\nend\nsleep(0.1)\n"
    )
    here = list(model.arm.state.q)
    steps = 0
    while model.program is not None and steps < 200:
        model.tick(model.step + 1)
        steps += 1
        if steps == 50:
            assert control_mode(model.program) == TORQUE
    events = [(e.kind, e.text) for e in model.drain_events()]
    assert not [e for e in events if e[0] == "runtime_exception"]
    assert 150 <= steps < 200  # one call a control step, then the sleep's 50
    assert list(model.arm.state.q) == here


@pytest.mark.parametrize(
    ("call", "message"),
    [
        ("direct_torque([0, 0, 0])", "torque must be six numbers"),
        ("direct_torque([0, 0, 0, 0, 0, 0], coulomb_scale=[2, 0, 0, 0, 0, 0])", "between 0 and 1"),
        ("direct_torque([0, 0, 0, 0, 0, 0], friction_comp=1)", "friction_comp must be a bool"),
    ],
)
def test_direct_torque_refuses_what_a_controller_refuses(call: str, message: str) -> None:
    _, events = run(call + "\n", version="5.26.0")
    assert any(kind == "runtime_exception" and message in text for kind, text in events), events


def test_the_mass_matrix_of_the_arm_at_rest_has_no_coriolis_torques() -> None:
    _, events = run("textmsg(norm(get_coriolis_and_centrifugal_torques()))\n")
    assert numbers(events) == [0.0]
    q = np.array(HOME_Q)
    assert np.all(dynamics.coriolis_torques(ControllerModel("5.23.0").arm.model, q, np.zeros(6)) == 0)
