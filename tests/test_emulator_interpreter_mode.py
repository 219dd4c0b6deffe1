"""Interpreter mode (e-Series 5.10 on), as UR's Script Directory (chapter 13 "Interpreter Mode") and
its article "Interpreter mode" describe it: a program calls `interpreter_mode()`, a client sends
URScript statements one line each on port 30020 and reads a reply line for each: `ack: <id>:
<statement>`, `discard: <reason>: <statement>`, or `state: <id>: <command>` for the state commands.

The client here talks as UR's own InterpreterHelper example does (the article's examples; public
copies, e.g. a screwdriver driver's InterpreterSocket and a Rust InterpreterClient, do the same): it
sends the statement with a "\\n" appended, reads bytes up to the "\\n", and reads the reply with the
pattern `(\\w+):\\W+(\\d+)?` (the kind of reply, and the id).
"""

from __future__ import annotations

import re
import socket
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.urscript.interpreter_mode import state_of

REPLY = re.compile(r"(\w+):\W+(\d+)?")  # InterpreterHelper's STATE_REPLY_PATTERN
TARGET = [0.5, -1.5, 1.5, -1.5, -1.5, 0.5]
PROGRAM = """def prog():
  x = 5
  interpreter_mode()
  if x == 6:
    set_standard_digital_out(2, True)
  end
end
"""


class Interpreter:
    """UR's InterpreterHelper, in short: one line out, one line back."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)

    def send(self, command: str) -> str:
        if not command.endswith("\n"):
            command += "\n"
        self.sock.sendall(command.encode("utf-8"))
        return self.reply()

    def reply(self) -> str:
        collected = b""
        while not collected.endswith(b"\n"):
            part = self.sock.recv(1)
            assert part, "the interpreter socket closed"
            collected += part
        return collected[:-1].decode("utf-8")

    def id_of(self, command: str) -> int:
        """sendCommand's value: the id of an ack or a state reply."""
        reply = self.send(command)
        found = REPLY.match(reply)
        assert found is not None and found.group(1) in ("ack", "state"), reply
        return int(found.group(2))

    def close(self) -> None:
        self.sock.close()


def wait_until(done: Callable[[], bool], seconds: float = 10.0) -> None:
    deadline = time.monotonic() + seconds
    while not done():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.02)


def in_interpreter_mode(emu: EmulatorThread) -> bool:
    program = emu.model.program
    return program is not None and state_of(program).active


@pytest.fixture
def emu() -> Iterator[EmulatorThread]:
    config = EmulatorConfig.free_ports(controller="5.15.0", realtime_port=None, dashboard_port=None)
    emulator = EmulatorThread(config).start()
    try:
        yield emulator
    finally:
        emulator.stop()


def start(emu: EmulatorThread, program: str = PROGRAM) -> Interpreter:
    """The program sent to the primary port, in interpreter mode; a client on the interpreter socket."""
    with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as primary:
        primary.sendall(program.encode())
    wait_until(lambda: in_interpreter_mode(emu))
    return Interpreter(emu.ports["interpreter"])


def actual_q(emu: EmulatorThread) -> list[float]:
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as robot:
        robot.setup_outputs(["actual_q"], 125)
        robot.start()
        return list(robot.receive().actual_q)


def test_a_movej_sent_is_acknowledged_with_its_id_and_moves_the_arm(emu: EmulatorThread) -> None:
    client = start(emu)
    try:
        statement = f"movej({TARGET}, a=1.5, v=1.5)"
        assert client.send(statement) == f"ack: 1: {statement}"
        assert client.id_of("set_standard_digital_out(1, True)") == 2
        assert client.id_of("statelastinterpreted") == 2
        wait_until(lambda: client.id_of("statelastexecuted") == 1)  # from the next control step
        assert client.send("stateunexecuted") == "state: 1: stateunexecuted"  # the move takes a second
        wait_until(lambda: client.id_of("statelastexecuted") == 2)
        assert actual_q(emu) == pytest.approx(TARGET, abs=1e-3)
        assert emu.model.values["actual_digital_output_bits"] & 0b10
        assert client.send("stateunexecuted") == "state: 0: stateunexecuted"
        assert client.send("statelastcleared") == "state: 0: statelastcleared"  # nothing cleared yet
    finally:
        client.close()


def test_statements_run_in_the_scope_interpreter_mode_was_called_from_and_end_interpreter_resumes(
    emu: EmulatorThread,
) -> None:
    client = start(emu)
    try:
        assert client.id_of("x = x + 1") == 1
        assert client.id_of("def blink(): set_standard_digital_out(3, True) end") == 2
        assert client.id_of("blink()") == 3
        assert client.send("end_interpreter()") == "ack: 4: end_interpreter()"
        wait_until(lambda: emu.model.program is None)  # the program went on past interpreter_mode()
        assert emu.model.values["actual_digital_output_bits"] & 0b1100 == 0b1100  # x was 6 there
        assert client.send("statelastcleared") == "state: 4: statelastcleared"  # clearOnEnd
        # no program runs now: statements are discarded, as the manual says
        assert client.send("textmsg(1)") == "discard: Program is in an invalid state: textmsg(1)"
    finally:
        client.close()


@pytest.mark.parametrize(
    ("statement", "reason"),
    [
        ("movej([1, 2", "Syntax error"),  # not whole
        ("fly_to(1)", "Compile error"),  # no such function
        ("global g = 1", "Compile error"),  # the manual: no new globals
        ("interpreter_mode()", "Compile error"),  # the manual: no nested interpreter modes
        ("movej([0, 0, 0, 0, 0, 0], 1, 1, 0, 0, 9)", "Compile error"),  # one argument too many
    ],
)
def test_a_statement_that_does_not_compile_is_discarded_and_the_mode_goes_on(
    emu: EmulatorThread, statement: str, reason: str
) -> None:
    client = start(emu)
    try:
        assert client.send(statement) == f"discard: {reason}: {statement}"
        assert client.id_of("statelastinterpreted") == 0  # it got no id
        assert client.send("textmsg(1)") == "ack: 1: textmsg(1)"
        assert in_interpreter_mode(emu)
    finally:
        client.close()


def test_lines_sent_before_interpreter_mode_wait_or_are_cleaned_up_on_entering(emu: EmulatorThread) -> None:
    """clearQueueOnEnter: True (the default) discards what was queued, False runs it."""
    waiting = "def prog():\n  sleep(0.5)\n  interpreter_mode(clearQueueOnEnter={})\nend\n"
    for keep in (False, True):
        with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as primary:
            primary.sendall(waiting.format(not keep).encode())
        wait_until(lambda: emu.model.program is not None)
        client = Interpreter(emu.ports["interpreter"])
        try:
            client.sock.sendall(b"set_standard_digital_out(4, True)\n")
            reply = client.reply()  # answered once interpreter mode is entered
            if keep:
                assert reply == "ack: 1: set_standard_digital_out(4, True)"
                wait_until(lambda: bool(emu.model.values["actual_digital_output_bits"] & 0b10000))
            else:
                assert reply == "discard: Cleaned up before interpretation: set_standard_digital_out(4, True)"
            assert in_interpreter_mode(emu)
            assert client.id_of("end_interpreter()") == 1 + keep
            wait_until(lambda: emu.model.program is None)
        finally:
            client.close()


def test_skipbuffer_skips_what_has_not_run_and_abort_stops_the_move(emu: EmulatorThread) -> None:
    client = start(emu)
    try:
        slow = "movej([1.5, -1.5, 1.5, -1.5, -1.5, 1.5], a=0.5, v=0.5)"
        assert client.id_of(slow) == 1
        assert client.id_of("set_standard_digital_out(5, True)") == 2
        assert client.id_of("set_standard_digital_out(6, True)") == 3
        wait_until(lambda: client.id_of("statelastexecuted") == 1)
        assert client.send("skipbuffer") == "state: 2: skipbuffer"  # two statements skipped
        assert client.send("stateunexecuted") == "state: 0: stateunexecuted"
        time.sleep(1.0)  # up to speed: 0.5 rad/s, a second's stop at 0.5 rad/s²
        assert client.send("abort") == "state: 1: abort"  # the movej under way stops
        assert client.id_of("set_standard_digital_out(7, True)") == 4
        braked = 0
        while emu.model.arm.motion is not None:  # a controlled stop: the next statement waits for it
            executed = client.id_of("statelastexecuted")
            assert executed == 1 or emu.model.arm.motion is None
            braked += 1
            time.sleep(0.05)
        assert braked > 2
        assert actual_q(emu)[0] < 1.0  # it stopped well short of the target
        assert emu.model.values["actual_digital_output_bits"] & 0b1100000 == 0
        wait_until(lambda: bool(emu.model.values["actual_digital_output_bits"] & 0b10000000))
        assert client.send("abort") == "state: 0: abort"  # nothing to abort
    finally:
        client.close()


def test_clear_interpreter_clears_what_was_interpreted(emu: EmulatorThread) -> None:
    """The manual: "Clears all interpreted statements, objects, functions, threads, etc."."""
    client = start(emu)
    try:
        assert client.id_of('def f(): textmsg("f") end') == 1
        assert client.id_of("f()") == 2
        assert client.id_of("thread ticker(): while True: sync() end end") == 3
        assert client.id_of("handle = run ticker()") == 4
        wait_until(lambda: len(emu.model.program.threads) == 2)  # type: ignore[union-attr]
        assert client.id_of("clear_interpreter()") == 5
        assert client.id_of("x = 7") == 6  # answered once the clear ran
        assert client.id_of("statelastcleared") == 5
        assert client.send("f()") == "discard: Compile error: f()"  # f went with the clear
        assert [t.name for t in emu.model.program.threads.values()] == ["prog"]  # type: ignore[union-attr]
    finally:
        client.close()


def test_interpreter_mode_only_in_the_main_thread(emu: EmulatorThread) -> None:
    program = "def prog():\n  thread t():\n    interpreter_mode()\n  end\n  h = run t()\n  sleep(1)\nend\n"
    model = emu.model
    with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as primary:
        primary.sendall(program.encode())
    wait_until(lambda: any(e.kind == "runtime_exception" for e in list(model.events)))
    faults = [e.text for e in model.drain_events() if e.kind == "runtime_exception"]
    assert faults == ["interpreter_mode() can only be called in the main thread"]


@pytest.mark.parametrize("version", ["5.9.0", "3.15.0"])
def test_before_5_10_and_on_cb3_there_is_no_interpreter_mode(version: str) -> None:
    """The article: "SW versions: 5.10 above, Robots: e-Series only"."""
    model = ControllerModel(version)
    model.run_script(PROGRAM)
    events = [(e.kind, e.text) for e in model.drain_events()]
    assert ("runtime_exception", "compile_error_name_not_found:interpreter_mode:") in events
    config = EmulatorConfig.free_ports(controller=version, realtime_port=None, dashboard_port=None)
    emu = EmulatorThread(config).start()
    try:
        assert "interpreter" not in emu.ports
    finally:
        emu.stop()
    config = EmulatorConfig.free_ports(controller="5.10.0", realtime_port=None, dashboard_port=None)
    emu = EmulatorThread(config).start()
    try:
        assert "interpreter" in emu.ports
    finally:
        emu.stop()


def test_bad_input_gets_its_reply_and_a_runtime_error_faults_the_program_not_the_port(
    emu: EmulatorThread,
) -> None:
    """Whatever a client sends, the port answers and keeps serving: bytes that are no UTF-8, a line
    too long to compile on the control loop, a statement that fails when it runs (the program's
    runtime exception, as any of its statements' would be)."""
    client = start(emu)
    try:
        client.sock.sendall(b"\xff\xfe\n")
        assert client.reply() == "discard: Syntax error: \ufffd\ufffd"
        huge = "x = [" + ",".join(["1.0"] * 5000) + "]"
        assert client.send(huge).startswith("discard: Statement too long: x = [1.0,")
        assert client.send("end") == "discard: Syntax error: end"
        assert client.send("z = 1 / 0") == "ack: 1: z = 1 / 0"
        wait_until(lambda: emu.model.program is None)
        assert client.send("statelastexecuted") == "state: 1: statelastexecuted"  # the last program's
        assert client.send("textmsg(1)") == "discard: Program is in an invalid state: textmsg(1)"
    finally:
        client.close()
    assert emu.emulator.late_steps == 0


def test_a_program_the_dashboard_plays_takes_statements_until_end_interpreter(tmp_path: Path) -> None:
    """The way the article's examples begin: a program that enters interpreter mode is loaded and
    played (here from the dashboard), a client sends statements, `end_interpreter()` ends it."""
    (tmp_path / "interpreter.script").write_text("def interpreter():\n  interpreter_mode()\nend\n")
    config = EmulatorConfig.free_ports(controller="5.15.0", realtime_port=None, programs=tmp_path)
    emu = EmulatorThread(config).start()
    try:
        with socket.create_connection(("127.0.0.1", emu.ports["dashboard"]), timeout=5) as dashboard:
            replies = dashboard.makefile("rb")
            replies.readline()
            for command in ("load interpreter.script", "play"):
                dashboard.sendall(command.encode() + b"\n")
                replies.readline()
            wait_until(lambda: in_interpreter_mode(emu))
            client = Interpreter(emu.ports["interpreter"])
            try:
                assert client.id_of(f"movej({TARGET}, a=3, v=3)") == 1
                assert client.id_of("end_interpreter()") == 2
                wait_until(lambda: emu.model.program is None)
            finally:
                client.close()
            dashboard.sendall(b"programState\n")
            assert replies.readline().decode().startswith("STOPPED")
        assert actual_q(emu) == pytest.approx(TARGET, abs=1e-3)  # the move ran to its end first
    finally:
        emu.stop()


def test_with_clear_on_end_false_what_was_interpreted_stays_for_the_next_interpreter_mode(
    emu: EmulatorThread,
) -> None:
    """clearOnEnd=False: "The interpreted statements will in that case be a part of the program until
    the end of program execution, thus they can be called/accessed in subsequent calls to
    interpreter_mode()". Ids go on from one interpreter mode to the next of the same program."""
    program = "def prog():\n  def helper():\n    textmsg(1)\n  end\n  interpreter_mode(clearOnEnd=False)\n"
    client = start(emu, program + "  interpreter_mode()\nend\n")
    try:
        assert client.id_of("def blink(): set_standard_digital_out(3, True) end") == 1
        # the program's own functions are not redefined (the emulator's choice: UR says nothing)
        assert (
            client.send("def helper(): textmsg(2) end")
            == "discard: Compile error: def helper(): textmsg(2) end"
        )
        assert client.id_of("end_interpreter()") == 2
        wait_until(lambda: client.id_of("statelastexecuted") == 2)
        wait_until(lambda: in_interpreter_mode(emu))  # the second one
        assert client.send("statelastcleared") == "state: 0: statelastcleared"  # nothing was cleared
        assert client.id_of("blink()") == 3
        wait_until(lambda: bool(emu.model.values["actual_digital_output_bits"] & 0b1000))
    finally:
        client.close()
