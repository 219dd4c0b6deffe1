"""PolyScope programs (.urp) the dashboard's `load` finds without their `.script`: the program
tree translated as PolyScope runs it (rtde_spec/emulator/controller/urp.py).

The control loop is the one UR's RTDE client ships as its example (`rtde_control_loop.urp` with
`example_control_loop.py`): a before-start sequence that sets a 1 Hz watchdog ("PAUSE", in
capitals, as UR's example writes it), a thread copying six input registers into a pose
variable, and a main program that moves linearly to that pose when the client says so and
hands back through an output register. The tree here is written as PolyScope saves one: the
expression one character per element, its operator glyphs, variables by XStream paths.
"""

from __future__ import annotations

import gzip
import logging
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec.emulator.controller.urp import UrpError, urp_to_script
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.rtde.client import RtdeClient

SETP1 = [-0.12, -0.43, 0.14, 0.0, 3.11, 0.04]
SETP2 = [-0.12, -0.51, 0.21, 0.0, 3.11, 0.04]


def chars(text: str) -> str:
    """An expression as PolyScope stores it: one element per character."""
    escape = {"&": "&amp;", '"': "&quot;", "<": "&lt;"}
    return "".join(f'<ExpressionChar character="{escape.get(c, c)}"/>' for c in text)


def line(text: str) -> str:
    return f'<Script type="Line"><expression>{chars(text)}</expression></Script>'


SETP_REF = "SpecialSequence/children/Assignment/variable"


def control_loop_urp(speed: float = 0.5) -> str:
    """UR's control loop program, node for node (the move faster, for a short test)."""
    return f"""<URProgram createdIn="3.2.19275.0" lastSavedIn="3.6.1.30595" name="rtde_control_loop">
  <children>
    <SpecialSequence type="BeforeStart"><children>
      <Assignment valueSource="Expression">
        <variable name="setp" prefersPersistentValue="false"><initializeExpression/></variable>
        <expression>{chars("p[0,0,0,0,0,0]")}</expression>
      </Assignment>
      {line('rtde_set_watchdog("input_int_register_0", 1, "PAUSE")')}
      {line("write_output_integer_register(0, 1)")}
    </children></SpecialSequence>
    <MainProgram runOnlyOnce="false" motionType="MoveJ" speed="1.0471975511965976">
      <children>
        <If type="If" checkContinuously="false">
          <expression>{chars("read_input_integer_register(0)≟1")}<ExpressionToken token=" and "/>
            <ExpressionVariable>
              <ProgramVariable reference="../../../../../../{SETP_REF}"/>
            </ExpressionVariable>
            {chars("≠p[0, 0, 0, 0, 0, 0]")}</expression>
          <children>
            <Comment comment="Valid pose received from client"/>
            <Move motionType="MoveL" speed="{speed}" acceleration="1.2" useActiveTCP="false">
              <feature class="GeomFeatureReference" referencedName="Joint_0_name"/>
              <children>
                <Waypoint type="Variable" name="Waypoint" kinematicsFlags="-1">
                  <motionParameters/>
                  <variable reference="../../../../../../../../{SETP_REF}"/>
                </Waypoint>
              </children>
            </Move>
            {line("write_output_integer_register(0, 0)")}
            <Loop type="While" checkContinuously="false">
              <expression>{chars("read_input_integer_register(0)≟1")}</expression>
              <children>{line("sync()")}</children>
            </Loop>
            {line("write_output_integer_register(0, 1)")}
          </children>
        </If>
        {line("sync()")}
      </children>
    </MainProgram>
    <Thread name="Thread_1" runOnlyOnce="false">
      <children>
        <Loop type="Forever"><children>
          <Assignment valueSource="Expression">
            <variable name="tmp" prefersPersistentValue="false"><initializeExpression/></variable>
            <expression>{chars("p[0,0,0,0,0,0]")}</expression>
          </Assignment>
          {"".join(line(f"tmp[{i}] = read_input_float_register({i})") for i in range(6))}
          <Assignment valueSource="Expression">
            <variable reference="../../../../../../{SETP_REF}"/>
            <expression>{chars("tmp")}</expression>
          </Assignment>
          {line("sync()")}
        </children></Loop>
      </children>
    </Thread>
  </children>
</URProgram>
"""


def test_the_control_loop_translates_as_polyscope_runs_it() -> None:
    script = urp_to_script(control_loop_urp().encode())
    lines = [s.strip() for s in script.splitlines()]
    assert lines[0] == "def rtde_control_loop():" and lines[-1] == "end"
    assert "global setp = p[0,0,0,0,0,0]" in lines
    assert "if read_input_integer_register(0)==1 and setp!=p[0, 0, 0, 0, 0, 0]:" in lines
    assert "movel(setp, a=1.2, v=0.5)" in lines
    assert "global setp = tmp" in lines  # the thread writes the program's variable
    assert lines.index("thread Thread_1():") < lines.index("thread_Thread_1 = run Thread_1()")
    assert lines.index("thread_Thread_1 = run Thread_1()") < lines.index(
        "while (True):", lines.index("thread_Thread_1 = run Thread_1()")
    )
    assert urp_to_script(gzip.compress(control_loop_urp().encode())) == script  # e-Series saves it gzip'd


@pytest.mark.parametrize(
    ("body", "problem"),
    [
        ('<Pallet name="p1"/>', r"MainProgram/Pallet\(p1\): <Pallet> is not a node the emulator reads"),
        ('<Move motionType="MoveC"><children/></Move>', "a MoveC move is not read"),
        (
            '<Assignment valueSource="Operator"><variable name="x"/></Assignment>',
            "an assignment from Operator",
        ),
        (
            '<Assignment><variable reference="../../../../Nothing/variable"/><expression/></Assignment>',
            "leads nowhere",
        ),
    ],
)
def test_what_cannot_be_run_as_polyscope_would_is_refused_naming_where(body: str, problem: str) -> None:
    main = f"<MainProgram><children>{body}</children></MainProgram>"
    urp = f'<URProgram name="x"><children>{main}</children></URProgram>'
    with pytest.raises(UrpError, match=problem):
        urp_to_script(urp.encode())


def test_fixed_waypoints_move_to_their_joint_angles() -> None:
    angles = "0.1,-1.5,1.2,-0.3,1.57,0.0"
    urp = f"""<URProgram name="fixed"><children><MainProgram runOnlyOnce="true"><children>
      <Move motionType="MoveJ" speed="1.05" acceleration="1.4"><children>
        <Waypoint type="Fixed" name="Waypoint_1">
          <position><JointAngles angles="{angles}"/></position>
        </Waypoint>
      </children></Move></children></MainProgram></children></URProgram>"""
    script = urp_to_script(urp.encode())
    assert "movej([0.1, -1.5, 1.2, -0.3, 1.57, 0.0], a=1.4, v=1.05)" in script
    assert "while (True)" not in script  # run once


def test_a_gzip_bomb_and_what_is_no_program_are_refused() -> None:
    with pytest.raises(UrpError, match="over"):
        urp_to_script(gzip.compress(b"<URProgram>" + b" " * (40 << 20)))
    with pytest.raises(UrpError, match="not a PolyScope program"):
        urp_to_script(b"<html/>")


class Dashboard:
    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.file = self.sock.makefile("rb")
        self.file.readline()

    def ask(self, command: str) -> str:
        self.sock.sendall(command.encode() + b"\n")
        return self.file.readline().decode().strip()


@pytest.fixture
def emu(tmp_path: Path) -> Iterator[EmulatorThread]:
    programs = tmp_path / "programs"
    programs.mkdir()
    (programs / "rtde_control_loop.urp").write_bytes(gzip.compress(control_loop_urp().encode()))
    (programs / "broken.urp").write_text('<URProgram name="b"><children><Pallet/></children></URProgram>')
    config = EmulatorConfig.free_ports(programs=programs)  # the real-time port too (it took 30003)
    emulator = EmulatorThread(config).start()
    yield emulator
    emulator.stop()


def test_a_program_that_cannot_be_translated_fails_to_load_and_the_log_says_why(
    emu: EmulatorThread, caplog: pytest.LogCaptureFixture
) -> None:
    dash = Dashboard(emu.ports["dashboard"])
    with caplog.at_level(logging.WARNING, logger="rtde_spec.emulator"):
        assert dash.ask("load broken.urp") == "Error while loading program: broken.urp"
    assert dash.ask("get loaded program") == "No program loaded"
    assert any("load broken.urp" in r.getMessage() and "<Pallet>" in r.getMessage() for r in caplog.records)


def test_ur_example_control_loop_moves_to_each_setpoint_and_hands_back(emu: EmulatorThread) -> None:
    """What `example_control_loop.py` does, step by step, against the loaded .urp."""
    dash = Dashboard(emu.ports["dashboard"])
    for command in ("power on", "brake release"):
        dash.ask(command)
    assert dash.ask("load rtde_control_loop.urp") == "Loading program: rtde_control_loop.urp"
    with RtdeClient("127.0.0.1", emu.ports["rtde"]) as con:
        con.setup_outputs(["actual_TCP_pose", "output_int_register_0"], 125)
        setp = con.setup_inputs([f"input_double_register_{i}" for i in range(6)])
        watchdog = con.setup_inputs(["input_int_register_0"])
        con.start()
        assert dash.ask("play") == "Starting program"
        for target in (SETP1, SETP2):
            deadline = time.monotonic() + 15
            # the pose first: the program's thread copies it in its own time (UR's example sends
            # it with the go-ahead, and the main program can take the go-ahead first)
            con.send(setp, {f"input_double_register_{i}": v for i, v in enumerate(target)})
            while con.receive(2).output_int_register_0 != 1:  # the program asks for a pose
                con.send(watchdog, input_int_register_0=0)
                assert time.monotonic() < deadline, "the program never asked for a pose"
            con.send(watchdog, input_int_register_0=1)
            while (state := con.receive(2)).output_int_register_0 != 0:  # moved: confirmed
                con.send(watchdog, input_int_register_0=1)
                assert time.monotonic() < deadline, "the move was never confirmed"
            assert list(state.actual_TCP_pose) == pytest.approx(target, abs=1e-4)
            con.send(watchdog, input_int_register_0=0)
        assert dash.ask("programState").startswith("PLAYING")
