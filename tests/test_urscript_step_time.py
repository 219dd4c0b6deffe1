"""A program's time in a control step, as the served emulator gives it: the time left before the
step is due (server/loop.py computes each step just before it is due), not a fixed 30% of the step.

URCL's external-control script costs the interpreter 0.4 to 0.8 ms of a 2 ms step at a spline
segment's start; a fixed slice of 0.6 ms preempted it there, the speedj of that step came a step
late, and URCL's splines ended up to 0.45 s late. Here a program whose every turn costs about 40%
of a step runs one turn in every step, as a robot runs it; with the fixed slice it ran one turn
in two.
"""

from __future__ import annotations

import time

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.emulator.controller.model import ControllerModel

SHARE = 0.4  # of a 500 Hz step: what one turn of the program costs
SECONDS = 1.0


def program(inner: int) -> str:
    return (
        "def prog():\n  global turns = 0\n  while True:\n    i = 0\n"
        f"    while i < {inner}:\n      i = i + 1\n    end\n"
        "    turns = turns + 1\n    sync()\n  end\nend\n"
    )


def cpu_per_turn(inner: int) -> float:
    """CPU seconds one turn costs, measured on a CB3 model (8 ms steps: never preempted)."""
    model = ControllerModel("3.15.0")
    started = model.run_script(program(inner))
    assert started is not None
    for _ in range(5):
        model.tick(model.step + 1)
    cpu, turns = time.thread_time(), started.globals["turns"]
    for _ in range(40):
        model.tick(model.step + 1)
    return (time.thread_time() - cpu) / (started.globals["turns"] - turns)


def test_a_turn_that_needs_40_percent_of_a_step_runs_in_every_step() -> None:
    per_iteration = (cpu_per_turn(400) - cpu_per_turn(100)) / 300
    inner = int(SHARE * 0.002 / per_iteration)
    assert 20 < inner < 4000  # a turn stays under the statement budget (10,000)
    config = EmulatorConfig(
        rtde_port=None, primary_port=None, secondary_port=None, realtime_port=None,
        dashboard_port=None, realtime_priority=50,
    )  # fmt: skip
    with EmulatorThread(config) as emu:
        started = emu.call(lambda: emu.model.run_script(program(inner)))
        assert started is not None
        time.sleep(0.1)
        steps, turns = emu.call(lambda: (emu.model.step, started.globals["turns"]))
        time.sleep(SECONDS)
        steps, turns = emu.call(lambda: (emu.model.step - steps, started.globals["turns"] - turns))
        events = emu.call(lambda: [(e.kind, e.text) for e in emu.model.drain_events()])
    assert not [text for kind, text in events if kind == "runtime_exception"], events
    # one turn a step (a fixed 30% slice: one in two, 250 of 500); on a machine whose other core is
    # busy a step now and then comes too late for its turn (446-454 of 500-521 seen at load 1)
    assert turns >= 0.8 * steps, (turns, steps, inner)
