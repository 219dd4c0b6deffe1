"""URScript control flow in the emulator: if/elif/else, while, break, continue, return, comparisons
and boolean logic, indexing; a loop that never waits faults instead of hanging the control step.

Programs go to the primary port of a running emulator (watched through primary messages, RTDE and
the dashboard) or straight to the controller model, stepped as the server steps it.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, PrimaryClient, RtdeClient
from rtde_spec._generated.enums import ProgramState
from rtde_spec.emulator.controller.model import HOME_Q, ControllerModel
from rtde_spec.emulator.controller.program import STEP_BUDGET

HZ = 500
A = [round(q + d, 6) for q, d in zip(HOME_Q, (0.1, 0.0, 0.0, 0.0, 0.0, 0.05), strict=True)]
B = [round(q + d, 6) for q, d in zip(HOME_Q, (-0.1, 0.0, 0.0, 0.0, 0.0, -0.05), strict=True)]


# --- helpers -------------------------------------------------------------------------------


def run(script: str, steps: int = 5 * HZ) -> tuple[ControllerModel, list[tuple[str, str, int, int]]]:
    """Run `script` on a fresh model until it ends (or `steps` control steps); its events."""
    model = ControllerModel("5.15.0")
    model.run_script(script)
    for _ in range(steps):
        if model.program is None:
            break
        model.tick(model.step + 1)
    return model, [(e.kind, e.text, e.line, e.column) for e in model.drain_events()]


def said(events: list[tuple[str, str, int, int]]) -> list[str]:
    return [text for kind, text, _, _ in events if kind == "text"]


def faults(events: list[tuple[str, str, int, int]]) -> list[tuple[str, int, int]]:
    return [(text, line, column) for kind, text, line, column in events if kind == "runtime_exception"]


def serve() -> EmulatorThread:
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=None, dashboard_port=0, realtime_port=None
    )
    return EmulatorThread(config).start()


def read_until(
    client: PrimaryClient, done: Callable[[list[object]], bool], seconds: float = 15.0
) -> list[object]:
    """Primary messages until `done(messages)` (robot states arrive at 10 Hz, so this never stalls)."""
    got: list[object] = []
    deadline = time.monotonic() + seconds
    for message in client:
        got.append(message)
        if done(got):
            return got
        assert time.monotonic() < deadline, f"timed out; got {[getattr(m, 'NAME', '') for m in got]}"
    raise AssertionError("the primary port closed")


def named(messages: list[object], name: str) -> list[object]:
    return [m for m in messages if getattr(m, "NAME", "") == name]


def texts(messages: list[object]) -> list[str]:
    return [m.text_message for m in named(messages, "text_message")]  # type: ignore[attr-defined]


def stopped(messages: list[object]) -> bool:
    titles = [m.robot_message_title for m in named(messages, "key_message")]  # type: ignore[attr-defined]
    return "PROGRAM_XXX_STOPPED" in titles


def dashboard(port: int, command: str) -> str:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        reader = sock.makefile("r")
        reader.readline()  # greeting
        sock.sendall(command.encode() + b"\n")
        return reader.readline().strip()


# --- loops through the running emulator ------------------------------------------------------


def test_a_while_loop_moves_to_alternating_targets_and_counts_three_turns() -> None:
    program = f"""def prog():
  i = 0
  while i < 3:
    if i % 2 == 0:
      movej({A}, a=3, v=3)
    else:
      movej({B}, a=3, v=3)
    end
    i = i + 1
    textmsg("turn ", i, " at ", get_actual_joint_positions()[0])
  end
  set_standard_digital_out(i, True)
end
"""
    emu = serve()
    try:
        with PrimaryClient("127.0.0.1", emu.ports["primary"], timeout=5) as client:
            client.send_script(program)
            got = read_until(client, stopped)
        with RtdeClient("127.0.0.1", emu.ports["rtde"]) as robot:
            robot.setup_outputs(["actual_q", "actual_digital_output_bits", "runtime_state"], 125)
            robot.start()
            record = robot.receive()
    finally:
        emu.stop()
    assert not named(got, "runtime_exception_message")
    assert texts(got) == [f"turn 1 at {A[0]:.6g}", f"turn 2 at {B[0]:.6g}", f"turn 3 at {A[0]:.6g}"]
    assert list(record.actual_q) == pytest.approx(A, abs=1e-6)
    assert record.actual_digital_output_bits == 1 << 3  # the counter after the loop: 3 turns
    assert record.runtime_state == ProgramState.STOPPED


def test_a_loop_that_never_waits_faults_with_its_line_and_the_emulator_keeps_serving() -> None:
    emu = serve()
    try:
        with (
            RtdeClient("127.0.0.1", emu.ports["rtde"]) as robot,
            PrimaryClient("127.0.0.1", emu.ports["primary"], timeout=5) as client,
        ):
            robot.setup_outputs(["timestamp", "actual_digital_output_bits"], 125)
            robot.start()
            first = robot.receive().timestamp
            started = time.monotonic()
            client.send_script("def busy():\n  x = 0\n  while True:\n    x = x + 1\n  end\nend\n")
            got = read_until(client, lambda got: bool(named(got, "runtime_exception_message")))
            assert time.monotonic() - started < 5
            [fault] = named(got, "runtime_exception_message")
            assert fault.script_line_number == 3  # type: ignore[attr-defined]
            text = fault.runtime_exception_text_message  # type: ignore[attr-defined]
            assert "did not yield" in text and "sync()" in text and "sleep()" in text
            stamps = [robot.receive().timestamp for _ in range(50)]  # the data still flows
            assert stamps == sorted(stamps) and stamps[-1] - stamps[0] > 0.2 and stamps[0] > first
            client.send_script("set_standard_digital_out(4, True)")  # and the next program runs
            deadline = time.monotonic() + 5
            while robot.receive().actual_digital_output_bits != 1 << 4:
                assert time.monotonic() < deadline, "the program after the fault did not run"
    finally:
        emu.stop()


def test_a_loop_with_sync_runs_one_turn_per_step_until_the_dashboard_stops_it() -> None:
    program = """def ticker():
  n = 0
  while True:
    n = n + 1
    if n % 250 == 0:
      textmsg("n=", n)
    end
    sync()
  end
end
"""
    emu = serve()
    try:
        with PrimaryClient("127.0.0.1", emu.ports["primary"], timeout=5) as client:
            client.send_script(program)
            got = read_until(client, lambda got: len(texts(got)) >= 3)
            assert texts(got)[:3] == ["n=250", "n=500", "n=750"]
            state = emu.call(lambda: emu.model.values["runtime_state"])
            assert state == ProgramState.RUNNING
            assert dashboard(emu.ports["dashboard"], "stop") == "Stopped"
            got = read_until(client, stopped)
        assert not named(got, "runtime_exception_message")
        assert emu.call(lambda: emu.model.program) is None
    finally:
        emu.stop()


def test_sync_in_a_loop_is_exactly_one_turn_per_control_step() -> None:
    model = ControllerModel("5.15.0")
    model.run_script(
        "n = 0\nwhile True:\n  n = n + 1\n  if n % 1000 == 0:\n    textmsg(n)\n  end\n  sync()\nend"
    )
    for _ in range(STEP_BUDGET + 500):  # more turns in all than one step may run: the budget is per step
        model.tick(model.step + 1)
    events = [(e.kind, e.text) for e in model.drain_events()]
    # the first turn runs when the program starts, then one per step: n = steps + 1
    assert [t for k, t in events if k == "text"] == [str(n) for n in range(1000, STEP_BUDGET + 501, 1000)]
    assert model.program is not None and not any(k == "runtime_exception" for k, _ in events)
    assert model.stop_program() and model.program is None


# --- branches, break, continue, return ---------------------------------------------------------

CHOOSER = """def pick(n):
  if n < 1:
    set_standard_digital_out(0, True)
  elif n == 1:
    set_standard_digital_out(1, True)
  elif n == 2 and not False:
    set_standard_digital_out(2, True)
  else:
    set_standard_digital_out(3, True)
  end
end
pick({n})
"""


@pytest.mark.parametrize(("n", "pin"), [(-4, 0), (1, 1), (2, 2), (2.5, 3), (7, 3)])
def test_if_elif_else_takes_the_branch_its_variable_chooses(n: float, pin: int) -> None:
    model, events = run(CHOOSER.format(n=n))
    assert not faults(events)
    assert model.values["actual_digital_output_bits"] == 1 << pin


def test_break_and_continue() -> None:
    _, events = run(
        """def prog():
  i = 0
  while i < 100:
    i = i + 1
    if i % 2 == 1:
      continue
    end
    if i >= 8:
      break
    end
    textmsg("even ", i)
  end
  textmsg("after ", i)
end"""
    )
    assert said(events) == ["even 2", "even 4", "even 6", "after 8"] and not faults(events)


def test_return_gives_a_value_to_an_expression_and_blocks_nest_in_a_def() -> None:
    _, events = run(
        """def clamp(x, low, high):
  if x < low:
    return low
  elif x > high:
    return high
  end
  return x
end
def scan():
  total = 0
  n = 0
  while n < 5:
    n = n + 1
    if n % 2 == 0:
      while True:
        total = total + clamp(n * 10, 0, 25)
        break
      end
    end
  end
  textmsg("total ", total, " ", clamp(-3, 0, 1) == 0)
end
scan()
"""
    )
    assert said(events) == ["total 45 True"] and not faults(events)  # 20 + clamp(40) = 25


def test_return_ends_the_program_def_and_an_index_can_be_assigned() -> None:
    model, events = run(
        """def prog():
  q = get_actual_joint_positions()
  kept = q
  q[0] = q[0] + 0.1
  movej(q, a=3, v=3)
  textmsg(kept[0] == q[0] - 0.1)
  if True:
    return
  end
  textmsg("not reached")
end"""
    )
    assert said(events) == ["True"] and not faults(events)  # q[0] = ... changed q only
    assert model.values["actual_q"][0] == pytest.approx(HOME_Q[0] + 0.1)


def test_a_struct_field_can_be_assigned_and_only_a_field_the_struct_has() -> None:
    """URCL's direct torque programs set `pd_controller_gains.kp = [...]` on a global struct."""
    _, events = run(
        """def prog():
  global gains = struct(kp=[1, 2], kd=3, inner=struct(x=1))
  kept = gains
  def tune():
    gains.kp = [4, 5]
    gains.kp[1] = 7
    gains.inner.x = 2
  end
  tune()
  textmsg(gains.kp, gains.kd, gains.inner.x, kept.kp)
  gains.ki = 1
end"""
    )
    assert said(events) == ["[4, 7]32[1, 2]"]
    assert faults(events) == [("Type error: struct has no field ki", 11, 3)]


def test_operators_follow_python_precedence() -> None:
    lines = [
        "1 + 2 * 3 == 7 and not 1 > 2 or False",  # True
        "not True == False",  # not (True == False): True
        "True or False and False",  # and before or: True
        "not (True or False) or 2 <= 1",  # False
        "True xor True",  # False
        "[1, 2] == [1, 2] and p[0, 0, 0, 0, 0, 1][5] == 1",  # True
        "-2 * 3 < -5 and 7 % 4 != 0 and 1.0 == 1 and 'a' != 'b'",  # True
    ]
    _, events = run("\n".join(f"textmsg({line})" for line in lines))
    assert said(events) == ["True", "True", "True", "False", "False", "True", "True"]


def test_a_function_that_waits_gives_its_value_when_its_motion_has_ended() -> None:
    """As on the controller (ur_rtde's `keep_running = process_cmd(cmd)` runs a movej inside)."""
    model, events = run(
        f"""def there():
  movej({A})
  return 1
end
def prog():
  textmsg("before")
  x = 2 * there()
  textmsg(x, " ", get_actual_joint_positions()[0])
end
prog()
"""
    )
    assert not faults(events)
    assert said(events) == ["before", f"2 {A[0]:.6g}"]
    assert model.values["actual_q"] == pytest.approx(A)


# --- faults with their lines ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("script", "text", "line", "column"),
    [
        (
            'def prog():\n  if True:\n    textmsg("a")\n  else:\n    textmsg("b")\n  elif False:\n  end\nend',
            "syntax_error_on_line:6:elif False:",
            6,
            3,
        ),
        (
            'def prog():\n  while True:\n    textmsg("a")\n    sync()\n  end\n  if True:\n    sync()\nend',
            "syntax_error_on_line:8:missing end of prog",
            8,
            1,
        ),
        ("if True:\n  sync()\n", "missing end of if on line 1", 2, 1),
        ('def prog():\n  textmsg("a")\n  else:\n  end\nend', "syntax_error_on_line:3:else:", 3, 3),
        (
            "def prog():\n  while True:\n    sync()\n  elif x:\n  end\nend",
            "syntax_error_on_line:4:elif x:",
            4,
            3,
        ),
        ('def prog():\n  textmsg("a")\n  break\nend', "syntax_error_on_line:3:break", 3, 3),
        ("return 1", "syntax_error_on_line:1:return 1", 1, 1),
        ("def prog():\n  while x < 1\n    sync()\n  end\nend", "syntax_error_on_line:2:", 2, 14),
        ("def prog():\n  textmsg(1)\n  if 1 < 2:\n    fly()\n  end\nend", "name_not_found:fly", 4, 5),
    ],
)
def test_what_cannot_be_compiled_names_its_line_and_nothing_runs(
    script: str, text: str, line: int, column: int
) -> None:
    model, events = run(script)
    assert [(kind, line_, col) for kind, _, line_, col in events] == [("runtime_exception", line, column)]
    assert text in events[0][1]
    assert model.program is None


@pytest.mark.parametrize(
    ("condition", "line", "column", "text"),
    [
        ('if "one":', 4, 6, "a condition must be a bool, not string"),
        ("while [1]:", 4, 9, "a condition must be a bool, not array"),
        ("if n > 0 and n:", 4, 16, "and's operand must be a bool, not int"),
        ("if n == 'one':", 4, 8, "Type error: int == string"),
        ("if [1][3] == 1:", 4, 9, "Index out of bounds: 3"),
    ],
)
def test_a_condition_that_is_no_bool_nor_number_is_a_runtime_exception_with_its_line(
    condition: str, line: int, column: int, text: str
) -> None:
    _, events = run(f'def prog():\n  n = 1\n  textmsg("ran")\n  {condition}\n    sync()\n  end\nend')
    assert said(events) == ["ran"]  # a run-time fault: what came before ran
    [(got, got_line, got_column)] = faults(events)
    assert text in got and (got_line, got_column) == (line, column)


def test_a_number_as_a_condition_is_true_unless_zero() -> None:
    """As in the ROS driver's program (UR's client library: `has_qnear = raw_point[15] /
    MULT_jointstate` then `if has_qnear:`), which runs on URSim in that library's tests."""
    script = (
        "def prog():\n  has_qnear = 1 / 1000000.0\n  none = 0\n"
        '  if has_qnear:\n    textmsg("float taken")\n  end\n'
        '  if none:\n    textmsg("zero taken")\n  elif 2:\n    textmsg("int taken")\n  end\n'
        "  k = 3\n  while k:\n    k = k - 1\n  end\n"
        '  textmsg("done")\nend'
    )
    _, events = run(script)
    assert said(events) == ["float taken", "int taken", "done"]
    assert not faults(events)
