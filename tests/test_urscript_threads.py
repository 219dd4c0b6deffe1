"""URScript threads, RTDE registers, sockets and the per-statement budgets, run as a controller runs them.

Threads advance within the control step and wait where a controller's do; the register
functions read and write the RTDE server's registers a client sees; sockets are real TCP
connections on loopback; a program that would take the control loop's time or the machine's
memory ends in the controller's error within a step or two, while the servers keep answering.
"""

from __future__ import annotations

import gc
import socket
import struct
import time

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.urscript import ScriptFault, parse
from tests.test_urscript_control import faults, said
from tests.test_urscript_control import run as run_script


def run(script: str, steps: int = 500) -> tuple[ControllerModel, list[tuple[str, str, int, int]]]:
    return run_script(script, steps)


def test_threads_advance_each_step_and_kill_and_join_end_them() -> None:
    _, events = run(
        """def prog():
  global ticks = 0
  thread counter():
    while True:
      ticks = ticks + 1
      sync()
    end
  end
  thread short():
    sleep(0.01)
    textmsg("short done")
  end
  t = run counter()
  sleep(0.1)
  kill t
  seen = ticks
  sleep(0.1)
  textmsg("ticks ", seen, " ", ticks == seen)
  s = run short()
  join s
  textmsg("joined")
end"""
    )
    assert not faults(events)
    [ticks, *rest] = said(events)
    # one turn per 2 ms step: the thread starts the step after `run`, and in each step the main
    # program runs first, so of the 50 steps the sleep lasts the thread saw 49; none after the kill
    assert ticks == "ticks 49 True"
    assert rest == ["short done", "joined"]


def test_a_new_program_ends_the_threads_of_the_last() -> None:
    model = ControllerModel("5.15.0")
    model.run_script("def a():\n  thread spin():\n    while True:\n      sync()\n    end\n  end\n"
                     "  run spin()\n  while True:\n    sync()\n  end\nend")  # fmt: skip
    for _ in range(5):
        model.tick(model.step + 1)
    first = model.program
    assert first is not None and len(first.threads) == 2
    model.run_script('textmsg("next")')
    assert first.finished and not first.threads


def test_a_thread_that_never_waits_is_the_controllers_runtime_error() -> None:
    started = time.perf_counter()
    busy = "  thread busy():\n    x = 0\n    while True:\n      x = x + 1\n    end\n  end\n"
    _, events = run(f"def prog():\n{busy}  run busy()\n  while True:\n    sync()\n  end\nend")
    [(text, line, _)] = faults(events)
    assert "Runtime is too much behind" in text and line == 4
    assert time.perf_counter() - started < 10  # steps, not minutes


def test_the_register_functions_are_the_rtde_servers_registers() -> None:
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=None, realtime_port=None, dashboard_port=None
    )
    with EmulatorThread(config) as emu, RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        client.setup_outputs(
            ["output_int_register_24", "output_double_register_30", "output_bit_registers0_to_31"], 500
        )
        inputs = client.setup_inputs(["input_int_register_24", "input_double_register_30"])
        client.start()
        emu.call(lambda: emu.model.run_script(
            "while True:\n  n = read_input_integer_register(24)\n  write_output_integer_register(24, n + 1)\n"
            "  write_output_float_register(30, read_input_float_register(30) * 2)\n"
            "  write_output_boolean_register(3, n > 10)\n  sync()\nend"))  # fmt: skip
        client.send(inputs, input_int_register_24=41, input_double_register_30=1.25)
        deadline = time.monotonic() + 5
        while True:
            got = client.receive()
            if got.output_int_register_24 == 42:
                break
            assert time.monotonic() < deadline
        assert got.output_double_register_30 == 2.5 and got.output_bit_registers0_to_31 == 1 << 3


def test_boolean_registers_64_to_127_are_rtdes_single_bit_fields() -> None:
    """The Script Manual gives the boolean registers addresses 0 to 127; RTDE carries 64 to 127 as
    BOOL fields of their own (input_/output_bit_register_X), the URCaps' range. Before, the emulator
    took 0 to 47, as for integers, and address 64 stopped the program."""
    config = EmulatorConfig(
        rtde_port=0, primary_port=None, secondary_port=None, realtime_port=None, dashboard_port=None
    )
    with EmulatorThread(config) as emu, RtdeClient("127.0.0.1", emu.ports["rtde"]) as client:
        client.setup_outputs(
            ["output_bit_register_70", "output_bit_registers32_to_63", "output_int_register_30"], 125
        )
        inputs = client.setup_inputs(["input_bit_register_65"])
        client.start()
        client.send(inputs, input_bit_register_65=True)
        emu.call(lambda: emu.model.run_script(
            "write_output_boolean_register(70, True)\nwrite_output_boolean_register(33, True)\n"
            "while not read_input_boolean_register(65):\n  sync()\nend\n"
            "write_output_integer_register(30, 7)\n"))  # fmt: skip
        deadline = time.monotonic() + 5
        while (got := client.receive()).output_int_register_30 != 7:
            assert time.monotonic() < deadline
        assert got.output_bit_register_70 is True and got.output_bit_registers32_to_63 == 1 << 1
    _, said_ = run("write_output_boolean_register(128, True)")
    assert "no register 128 (0 to 127)" in str(said_)


def test_sockets_connect_to_the_clients_port_and_carry_ints_strings_and_floats() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server:
        port = server.getsockname()[1]
        model = ControllerModel("5.15.0")
        model.run_script(
            f"""def prog():
  ok = socket_open("127.0.0.1", {port}, "link")
  socket_send_int(7, "link")
  socket_send_string("hello", "link")
  got = socket_read_binary_integer(2, "link", 1.0)
  floats = socket_read_ascii_float(2, "link")
  textmsg(ok, " ", got, " ", floats)
  socket_close("link")
  missing = socket_read_binary_integer(1, "link", 0.01)
  textmsg(missing)
end"""
        )
        server.settimeout(5)
        for _ in range(3):
            model.tick(model.step + 1)
        peer, _ = server.accept()
        with peer:
            peer.sendall(struct.pack(">ii", -5, 1 << 20) + b"(1.5, -2.25)")
            for _ in range(20):
                model.tick(model.step + 1)
            peer.settimeout(2)
            data = peer.recv(64)
            assert data == struct.pack(">i", 7) + b"hello"
            assert peer.recv(64) == b""  # closed by socket_close
    texts = [e.text for e in model.drain_events() if e.kind == "text"]
    assert texts == ["True [2, -5, 1048576] [2, 1.5, -2.25]", "[0, -1]"]


def test_socket_open_to_a_closed_port_is_false_and_names_are_not_looked_up() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server:
        port = server.getsockname()[1]
    _, events = run(f'textmsg(socket_open("127.0.0.1", {port}), socket_open("localhost", 80))')
    assert said(events) == ["FalseFalse"]


@pytest.mark.parametrize(
    ("script", "text"),
    [
        ("a = [1]\nb = [1]\n" + "a = [a, a]\nb = [b, b]\n" * 32 + "c = a == b\n", "arrays nest at most"),
        ("a = [1.0]\n" + "a = [a, a]\n" * 26 + "n = norm(a)\n", "arrays nest at most"),
        ('s = "xy"\nwhile True:\n  s = str_cat(s, s)\n  sync()\nend', "text over"),
        ("def f(n):\n  return f(n + 1)\nend\nf(0)", "calls nested deeper"),
    ],
)
def test_programs_that_would_take_the_machine_end_in_a_runtime_error_at_once(script: str, text: str) -> None:
    started = time.perf_counter()
    model, events = run(script, steps=100)
    [(got, _, _)] = faults(events)
    assert text in got and model.program is None
    assert time.perf_counter() - started < 10  # steps, not minutes


def test_parsing_is_linear_and_a_huge_program_is_refused() -> None:
    def call_over(lines: int) -> float:
        text = "textmsg(1" + ",\n1" * lines + ")\n"
        gc.collect()
        gc.disable()  # a collection inside one run is not the parser's cost
        try:
            started = time.process_time()  # this process's CPU: other load does not count
            parse(text)
            return time.process_time() - started
        finally:
            gc.enable()

    small = min(call_over(8_000) for _ in range(3))
    large = min(call_over(64_000) for _ in range(3))
    assert large < small * 20  # 8x the lines: about 8x the time, where quadratic parsing took 64x
    with pytest.raises(ScriptFault, match="syntax_error_on_line:1:program over"):
        parse("x = 1\n" * (2 << 20))


def test_continuation_lines_and_statements_side_by_side_as_ur_rtde_sends_them() -> None:
    _, events = run(
        "def prog():\n  global a = # a comment, then the value\n0    global b = [1,\n  2] # more\n"
        '  c = a +\n    b[1] * 3\n  p = p[1, 2, 3, 0, 0, 0]\n  p[0] = p[0] + 1\n  textmsg(c, " ", p[0])\nend'
    )
    assert not faults(events) and said(events) == ["6 2"]


@pytest.mark.parametrize(("action", "paused", "stopped"), [("stop", False, True), ("pause", True, False)])
def test_rtde_set_watchdog_acts_when_the_client_goes_silent(action: str, paused: bool, stopped: bool) -> None:
    model = ControllerModel("5.15.0")
    model.run_script(
        f'rtde_set_watchdog("input_int_register_24", 10, "{action}")\nwhile True:\n  sync()\nend'
    )
    for step in range(200):  # 0.4 s with the client writing every 20 ms: nothing happens
        if step % 10 == 0:
            model.apply_inputs({"input_int_register_24": step})
        model.tick(model.step + 1)
    assert model.program is not None and not model.paused
    for _ in range(60):  # then silence: past 0.1 s the watchdog acts
        model.tick(model.step + 1)
    events = [(e.kind, e.text) for e in model.drain_events()]
    assert model.paused is paused and (model.program is None) is stopped
    text = "RTDE input watchdog: input_int_register_24 not written at 10 Hz"
    assert (("runtime_exception", text) in events) is stopped


def test_the_program_defs_variables_are_the_globals_its_threads_see_and_join_of_0_returns() -> None:
    """As URCL's external control program: `control_mode = ...` in the program def, read by threads;
    `join thread_move` while no thread was started (0)."""
    _, events = run(
        """def program():
  mode = 0
  worker = 0
  thread watcher():
    while mode == 1:
      sync()
    end
    textmsg("watcher saw mode ", mode)
  end
  join worker
  mode = 1
  worker = run watcher()
  sleep(0.02)
  mode = 2
  join worker
  textmsg("joined")
end"""
    )
    assert not faults(events) and said(events) == ["watcher saw mode 2", "joined"]


def test_a_long_program_is_read_off_the_control_loop() -> None:
    """A call spread over 64,000 lines (about 190 KB) is parsed in a worker thread: the control
    steps go on meanwhile, and the program starts in a later step; evaluating its 64,000
    arguments takes more than the step's budget, so it ends in the controller's runtime error."""
    model = ControllerModel("5.15.0")
    model.run_script("textmsg(1" + ",\n1" * 64_000 + ")\n")
    assert model.program is None  # not started yet: being read
    steps = 0
    while not model.events and steps < 20_000:
        model.tick(model.step + 1)
        steps += 1
        time.sleep(0.0005)
    events = model.drain_events()
    assert [e.kind for e in events][:2] == ["program_started", "runtime_exception"] and steps > 1
    assert "Runtime is too much behind: line 1" in events[1].text and events[1].line == 1


def test_arrays_of_numbers_add_and_scale_element_by_element() -> None:
    """URCL's extrapolate(): `cmd_servo_q + (get_target_joint_speeds() * steptime)`."""
    _, events = run('textmsg([1, 2] + [0.5, 1] * 2, " ", [1, 2] - 1, " ", [4, 8] / 2)\nx = [1, 2] + [1]')
    assert said(events) == ["[2, 4] [0, 1] [2, 4]"]
    [(text, line, _)] = faults(events)
    assert "arrays of 2 and 1 elements" in text and line == 2
