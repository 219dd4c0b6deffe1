"""random() and make_list(), the Script Directory's urmath functions that make a value: programs
call them (UR's examples seed lists with make_list), so a controller that lacks them refuses them."""

from __future__ import annotations

from rtde_spec.emulator.controller.model import ControllerModel

from .test_urscript_control import faults, run, said


def test_random_gives_floats_from_0_to_1_that_differ() -> None:
    _, events = run(
        "def prog():\n  i = 0\n  while i < 20:\n    textmsg(random())\n    i = i + 1\n  end\nend\n"
    )
    values = [float(text) for text in said(events)]
    assert len(values) == 20 and all(0 <= v <= 1 for v in values)
    assert len(set(values)) > 1


def test_a_built_in_given_more_arguments_than_it_has_is_a_compile_error_at_the_call() -> None:
    """Arguments past a built-in's parameters were dropped unseen (norm(1, 2) was 1)."""
    for call, message in (
        ("random(3)", "random takes at most 0 arguments, got 1"),
        ("make_list(1, 0, 1, 1)", "make_list takes at most 3 arguments, got 4"),
        ("norm(1, 2)", "norm takes at most 1 arguments, got 2"),
        (
            "wrench_trans(p[0, 0, 0, 0, 0, 0], [1, 2, 3, 4, 5, 6], 1)",
            "wrench_trans takes at most 2 arguments",
        ),
        (
            "pose_dist(p[0, 0, 0, 0, 0, 0], p[0, 0, 0, 0, 0, 0], p_from=p[0, 0, 0, 0, 0, 0])",
            "pose_dist p_from given twice",
        ),
    ):
        _, events = run(f"def prog():\n  x = 1\n  y = {call}\nend\n")
        ((text, line, column),) = faults(events)
        assert text.startswith(f"compile_error: {message}") and (line, column) == (3, 7), (call, text)


def test_make_list_gives_the_manuals_lists() -> None:
    _, events = run(
        "def prog():\n"
        '  textmsg(make_list(5, "a"))\n'
        "  textmsg(make_list(3, 0, 100))\n"
        "  textmsg(length(make_list(0, 0, 100)))\n"
        "  textmsg(make_list(2, p[0.1, 0, 0, 0, 0, 0]))\n"
        "end\n"
    )
    assert said(events) == [
        "[a, a, a, a, a]",
        "[0, 0, 0]",
        "0",
        "[p[0.1, 0, 0, 0, 0, 0], p[0.1, 0, 0, 0, 0, 0]]",
    ]


def test_make_list_of_structs_gives_each_element_its_own() -> None:
    _, events = run(
        "def prog():\n  l = make_list(2, struct(a=1))\n  l[0].a = 5\n  textmsg(l[0].a, l[1].a)\nend\n"
    )
    assert not faults(events)
    assert said(events) == ["51"]


def test_make_list_refuses_what_the_manual_rules_out() -> None:
    for call, message in (
        ("make_list(2, [1, 2])", "initial_value cannot be an array"),
        ("make_list(5, 0, 2)", "capacity 2 is less than length 5"),
        ("make_list(-1, 0)", "length must be an int"),
        ('make_list("3", 0)', "length must be an int"),
        ("make_list(3)", "missing argument initial_value"),
    ):
        _, events = run(f"def prog():\n  x = 1\n  l = {call}\nend\n")
        ((text, line, _),) = faults(events)
        assert text.startswith("make_list: ") and message in text and line == 3, (call, text)


def run_on(version: str, script: str, steps: int = 20) -> list[tuple[str, str, int]]:
    model = ControllerModel(version)
    model.run_script(script)
    for _ in range(steps):
        if model.program is None:
            break
        model.tick(model.step + 1)
    return [(e.kind, e.text, e.line) for e in model.drain_events()]


def test_get_rtde_value_reads_an_rtde_output_as_clients_receive_it() -> None:
    """UR's impedance-control example (for 5.23) times itself with get_rtde_value."""
    events = run_on(
        "5.23.0",
        "def prog():\n"
        '  textmsg(get_rtde_value("actual_execution_time"))\n'
        '  textmsg(get_rtde_value("actual_q")[1])\n'
        '  textmsg(get_rtde_value("robot_mode"))\n'
        '  x = get_rtde_value("no_such_output")\n'
        "end\n",
    )
    assert [text for kind, text, _ in events if kind == "text"] == ["0", "-1.5708", "7"]  # the home pose
    faults = [(text, line) for kind, text, line in events if kind == "runtime_exception"]
    assert faults == [("get_rtde_value: no RTDE output 'no_such_output' on this controller", 5)]


def test_get_rtde_value_is_refused_before_5_23() -> None:
    events = run_on("5.22.0", 'def prog():\n  x = get_rtde_value("actual_q")\nend\n')
    assert ("runtime_exception", "compile_error_name_not_found:get_rtde_value:", 2) in events


def test_time_reads_the_controller_s_clock_by_default_and_the_system_time_with_mode_2() -> None:
    """The e-Series Script Directory's time(mode=0): 0 the controller's execution time since it
    started (its example: current_time_s = time().sec), 2 the system time in GMT, 1 reserved."""
    events = run_on(
        "5.22.0",
        "def prog():\n"
        "  sleep(0.5)\n"
        "  t = time()\n"
        "  textmsg(t.sec + t.nanosec / 1000000000)\n"
        "  textmsg(time(2).sec > 1700000000, time(0).sec < 10)\n"
        "  x = time(1)\n"
        "end\n",
        steps=400,
    )
    texts = [text for kind, text, _ in events if kind == "text"]
    assert 0.49 < float(texts[0]) < 0.6 and texts[1] == "TrueTrue"
    faults = [(text, line) for kind, text, line in events if kind == "runtime_exception"]
    assert faults == [("time: mode must be 0 (controller) or 2 (system time), not 1", 6)]


def test_reachability_takes_the_manuals_parameters_and_the_tcp_it_is_given() -> None:
    """get_inverse_kin_has_solution(pose, qnear, maxPositionError, maxOrientationError, tcp) and
    is_within_safety_limits(position, qNear): the same pose with a TCP 5 m long is out of reach."""
    events = run_on(
        "5.15.0",
        "def prog():\n"
        "  x = get_actual_tcp_pose()\n"
        "  long = p[0, 0, 5, 0, 0, 0]\n"
        "  textmsg(get_inverse_kin_has_solution(x), get_inverse_kin_has_solution(x, tcp=long))\n"
        "  q = get_actual_joint_positions()\n"
        "  textmsg(is_within_safety_limits(position=x), is_within_safety_limits(x, q))\n"
        "end\n",
    )
    assert [text for kind, text, _ in events if kind == "text"] == ["TrueFalse", "TrueTrue"]


def test_make_list_copies_stay_within_what_a_value_may_hold() -> None:
    """Copies of a struct holding a list multiply its elements: 1,000 copies of 2,000 would be two
    million, past the 65,536 a value holds (a bigger make_list would take the emulator's memory)."""
    _, events = run(
        "def prog():\n"
        "  s = struct(a = make_list(2000, 0))\n"
        "  l = make_list(1000, s)\n"
        "  m = make_list(30, s)\n"
        "  textmsg(length(m))\n"
        "end\n"
    )
    assert faults(events) == [
        ("make_list: 1000 of this initial value hold over 65536 elements (a value holds at most that)", 3, 1)
    ]
