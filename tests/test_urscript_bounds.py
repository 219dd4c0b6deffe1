"""Every statement of a URScript program is bounded in time and memory, not only the program.

A value holds at most MAX_ELEMENTS elements through its lists and nests at most MAX_NESTING
deep, however it is built (a list literal, `a[0] = a`); a thread that runs on without waiting is
preempted at the end of the interpreter's slice of the step and faults after STEP_BUDGET
statements; a program whose process grows past MEMORY_BUDGET faults "out of memory" and what it
held is given back. The interpreter never hands program text to Python's eval/exec/compile.
"""

from __future__ import annotations

import ast
import gc
import time
from pathlib import Path

from rtde_spec.emulator.urscript import evaluator, interpreter
from rtde_spec.emulator.urscript.interpreter import resident_bytes
from tests.test_urscript_control import faults
from tests.test_urscript_control import run as run_script

URSCRIPT = Path(evaluator.__file__).parent


def test_a_wide_three_deep_list_is_refused_when_it_is_built_not_when_compared() -> None:
    """41 x 41 x 41 = 68,921 elements: `c = a == b` of two such values once took minutes."""
    row = "[" + ", ".join(["1"] * 41) + "]"
    script = (
        f"r = {row}\ns = {row}\n"
        + "a = [" + ", ".join(["r"] * 41) + "]\nb = [" + ", ".join(["s"] * 41) + "]\n"
        + "A = [" + ", ".join(["a"] * 41) + "]\nB = [" + ", ".join(["b"] * 41) + "]\nc = A == B\n"
    )  # fmt: skip
    model, events = run_script(script, 10)
    [(text, line, _)] = faults(events)
    assert f"holds at most {evaluator.MAX_ELEMENTS} elements" in text and line == 5
    assert model.program is None


def test_a_list_assigned_into_itself_cannot_nest_deeper_each_turn() -> None:
    _, events = run_script("a = [1, 2]\nwhile True:\n  a[0] = a\n  sync()\nend\n", 20)
    [(text, line, _)] = faults(events)
    assert f"nest at most {evaluator.MAX_NESTING} deep" in text and line == 3


def test_shape_counts_a_shared_list_each_time_it_is_held_but_walks_it_once() -> None:
    row = [1.0] * 100
    square = [row] * 100
    assert evaluator.shape(square) == (2, 10_000)
    cube = [square] * 100  # a million elements, three lists walked
    depth, count = evaluator.shape(cube)
    assert depth == 3 and count > evaluator.MAX_ELEMENTS


def test_a_thread_that_never_waits_is_preempted_at_its_slice_then_faults_after_the_budget() -> None:
    _, events = run_script(
        "def prog():\n  thread busy():\n    x = 0\n    while True:\n      x = x + 1\n    end\n  end\n"
        "  run busy()\n  n = 0\n  while True:\n    n = n + 1\n    sync()\n  end\nend\n",
        steps=2000,
    )
    [(text, line, _)] = faults(events)
    assert "Runtime is too much behind: the loop on line 4 did not yield" in text and line == 4
    assert "without a wait" in text


def test_preemption_spreads_a_long_loop_over_steps_and_the_main_program_keeps_its_turns() -> None:
    """A loop of 3,000 turns without a wait (6,000 statements, under the budget) ends without a
    fault; while it runs the main program still gets one turn in every step."""
    from rtde_spec.emulator.controller.model import ControllerModel

    model = ControllerModel("5.15.0")
    program = model.run_script(
        "def prog():\n  global done = False\n  thread work():\n    i = 0\n    while i < 3000:\n"
        "      i = i + 1\n    end\n    done = True\n  end\n  run work()\n  turns = 0\n"
        "  while not done:\n    turns = turns + 1\n    sync()\n  end\n  textmsg(turns)\nend\n"
    )
    assert program is not None
    for _ in range(500):
        if model.program is None:
            break
        model.tick(model.step + 1)
    events = [(e.kind, e.text) for e in model.drain_events()]
    assert not [e for e in events if e[0] == "runtime_exception"], events
    turns = int(next(text for kind, text in events if kind == "text"))
    assert program.preemptions > 0  # the worker went on over several steps
    assert turns > program.preemptions  # and the main program had its turn in each of them


def test_a_program_that_allocates_without_end_stops_out_of_memory_and_gives_it_back() -> None:
    """Each step keeps another 1 MB text under a new name; past MEMORY_BUDGET the program faults."""
    from rtde_spec.emulator.controller.model import ControllerModel

    names = 3 * (interpreter.MEMORY_BUDGET >> 20)  # room to fault even if what earlier tests freed
    gc.collect()  # is given back while this runs (the budget counts from the program's start)
    grow = "".join(f"  x{i} = str_cat(s, s)\n  sync()\n" for i in range(names))
    double = "  while i < 18:\n    s = str_cat(s, s)\n    i = i + 1\n  end\n"  # 2**19 characters
    script = f'def hog():\n  s = "xy"\n  i = 0\n{double}{grow}end\n'
    model = ControllerModel("5.15.0")
    before = resident_bytes()
    model.run_script(script)
    while model._parsing:  # a long program is read off the control loop
        model.tick(model.step + 1)
        time.sleep(0.001)
    peak = 0
    for _ in range(names + 20):
        if model.program is None:
            break
        model.tick(model.step + 1)
        peak = max(peak, resident_bytes())
    events = [(e.kind, e.text) for e in model.drain_events()]
    [text] = [text for kind, text in events if kind == "runtime_exception"]
    assert text.startswith(f"out of memory: the program holds over {interpreter.MEMORY_BUDGET >> 20} MB")
    assert peak - before < interpreter.MEMORY_BUDGET + (64 << 20)
    assert resident_bytes() - before < 64 << 20  # the texts went with the program


def test_the_interpreter_never_hands_program_text_to_eval_exec_or_compile() -> None:
    """Read from the source: no module of urscript/ calls eval, exec, compile or __import__."""
    banned = {"eval", "exec", "compile", "__import__"}
    found = []
    for path in sorted(URSCRIPT.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Call):
                fn = node.func
                name = fn.id if isinstance(fn, ast.Name) else fn.attr if isinstance(fn, ast.Attribute) else ""
                if name in banned and not (isinstance(fn, ast.Attribute) and name == "compile"):
                    found.append(f"{path.name}:{node.lineno} {name}")
    assert len(list(URSCRIPT.glob("*.py"))) >= 8  # lexer, parser, checker, interpreter, ...
    assert found == []


def test_a_function_run_inside_an_expression_may_take_milliseconds_under_the_statement_budget() -> None:
    """Once it faulted: a step's CPU past 4 ms (a full garbage collection, a long function inside an
    expression) was blamed on the statement running then, and ur_rtde's control script stopped."""
    function = "def f():\n  i = 0\n  while i < 4000:\n    i = i + 1\n  end\n  return i\nend\n"
    _, events = run_script(function + "x = f() + 1\ntextmsg(x)\n", 10)
    assert not faults(events)
    assert [text for kind, text, _, _ in events if kind == "text"] == ["4001"]
