"""The ROS driver's path through the emulator, end to end: a test client of URCL's external
control (tests/external_driver.py, written from spec/external_control/) plays the driver.

It readies the arm with the primary port's plain commands as URCL does (`power on`,
`set robotmode run`, `stop program`), sends an external-control program in the style of
URCL's (tests/data/external_control_driver.urscript: threads, named sockets back to the
driver's reverse, trajectory and script command servers, time-outs as keepalives) headless
on the primary port, then drives it: servoj targets and keepalives on the reverse port,
trajectory points with timing on the trajectory port (their result comes back there),
script commands on the script command port. The arm is seen through RTDE (actual_q, TCP
pose, payload, TCP offset, tool voltage) and the primary port (robot mode, text messages).
Every server is on a free port.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, RtdeClient
from rtde_spec.emulator.arm import kinematics as kin
from rtde_spec.emulator.controller.model import HOME_Q, ControllerModel
from rtde_spec.metamodel.arms import arm_model
from tests.external_driver import DriverSide, PrimaryWatch, straight

RAD, METRE = 1e-4, 1e-4
POWER_OFF, IDLE, RUNNING = 3, 5, 7  # RobotMode
POSITION, TEACH, FORCE = 0, 1, 2  # ControlMode of the Robot Mode Data
OUTPUTS = ["timestamp", "actual_q", "actual_qd", "actual_TCP_pose", "actual_TCP_speed", "payload",
           "payload_cog", "tcp_offset", "tool_output_voltage", "runtime_state"]  # fmt: skip


@dataclass
class Session:
    emu: EmulatorThread
    primary: PrimaryWatch
    driver: DriverSide
    rtde: RtdeClient

    def latest(self) -> Any:
        """The newest RTDE record (the ones queued before it are dropped)."""
        record = self.rtde.receive(timeout=5)
        while True:
            try:
                record = self.rtde.receive(timeout=0.001)
            except TimeoutError:
                return record

    def q(self) -> list[float]:
        """The joints of the arm at rest (see `still`)."""
        return list(self.still().actual_q)

    def still(self, seconds: float = 5.0) -> Any:
        """The newest record once the arm rests: no joint speed, the same joints in two records of
        the controller 40 ms apart. An answer on a socket can come before the RTDE record of the
        same control step (after a stall, before the steps it catches up), so a record is not
        taken for the end until a later one agrees."""
        deadline = time.monotonic() + seconds
        last = self.latest()
        while True:
            time.sleep(0.04)
            record = self.latest()
            if (
                record.timestamp > last.timestamp
                and not any(record.actual_qd)
                and list(record.actual_q) == list(last.actual_q)
            ):
                return record
            assert time.monotonic() < deadline, f"the arm did not come to rest within {seconds} s"
            last = record

    def until(self, done: Any, seconds: float, what: str, keepalive: bool = True) -> Any:
        """Keep the program alive (as the driver's loop does) until `done(record)`; the record."""
        deadline = time.monotonic() + seconds
        while True:
            record = self.latest()
            if done(record):
                return record
            assert time.monotonic() < deadline, f"{what}: not within {seconds} s ({self.primary.texts[-6:]})"
            if keepalive:
                self.driver.keepalive()
            time.sleep(0.02)


def start(emu: EmulatorThread) -> Iterator[Session]:
    primary = PrimaryWatch("127.0.0.1", emu.ports["primary"])
    driver = DriverSide()
    rtde = RtdeClient("127.0.0.1", emu.ports["rtde"]).connect()
    try:
        rtde.setup_outputs(OUTPUTS, 125)
        rtde.start()
        yield Session(emu, primary, driver, rtde)
    finally:
        rtde.close()
        driver.close()
        primary.close()


@pytest.fixture
def session() -> Iterator[Session]:
    with EmulatorThread(
        EmulatorConfig(
            rtde_port=0, primary_port=0, secondary_port=None, realtime_port=None, dashboard_port=None
        )
    ) as emu:
        yield from start(emu)


def ready_and_run(s: Session) -> None:
    """The driver's start-up: a powered, released arm, no program, then its program, connected back."""
    primary, driver = s.primary, s.driver
    primary.wait(lambda w: w.mode is not None, 5, "a Robot State")
    primary.send("power off")
    primary.wait(lambda w: w.mode.robot_mode == POWER_OFF, 5, "POWER_OFF after power off")
    primary.send("power on")
    primary.wait(lambda w: w.mode.robot_mode == IDLE and w.mode.is_robot_power_on, 5, "IDLE after power on")
    primary.send("stop program")
    primary.send("set robotmode run")  # URCL's brake release
    primary.wait(lambda w: w.mode.robot_mode == RUNNING, 5, "RUNNING after set robotmode run")
    primary.send(driver.program())
    driver.accept()
    primary.wait_text("external control active")
    primary.wait(lambda w: w.mode.is_program_running, 5, "the program running")


@pytest.mark.slow  # a whole driver session: CI runs it
def test_the_driver_readies_the_arm_streams_servoj_runs_a_trajectory_and_sends_script_commands(
    session: Session,
) -> None:
    s, driver = session, session.driver
    ready_and_run(s)
    assert not s.primary.exceptions

    # servoj targets on the reverse port: a ramp at 500 Hz, then the last target held
    home = s.q()
    goal = [home[0] + 0.2, home[1] - 0.1, home[2] + 0.1, home[3], home[4], home[5] - 0.2]
    servoj = driver.mode("SERVOJ")
    steps = 250
    for i in range(steps + 1):
        driver.write_command(straight(home, goal, i / steps), servoj, read_timeout=0.5)
        time.sleep(0.002)
    for _ in range(50):
        driver.write_command(goal, servoj, read_timeout=0.5)
        time.sleep(0.002)
    record = s.until(lambda r: list(r.actual_q) == pytest.approx(goal, abs=RAD), 5, "the servoj target")
    s.primary.wait(lambda w: w.q == pytest.approx(goal, abs=RAD), 5, "the servoj target in the Robot State")

    # a trajectory: two joint points with durations, then a linear point, forwarded on 50003
    first = [goal[0] - 0.3, goal[1] + 0.1, goal[2] - 0.1, goal[3] + 0.1, goal[4], goal[5] + 0.3]
    second = [first[0] + 0.1, *first[1:5], first[5] - 0.1]
    model = arm_model("UR5e")
    pose = kin.forward(model, second)
    third = [pose[0], pose[1] + 0.05, pose[2] - 0.03, *pose[3:]]
    driver.trajectory_control("START", points=3)
    started = time.monotonic()
    driver.write_point("MOVEJ", first, duration=0.6)
    driver.write_point("MOVEJ", second, duration=0.4)
    driver.write_point("MOVEL", third, velocity=0.25, acceleration=1.2)
    assert driver.trajectory_result(seconds=10) == "SUCCESS"
    took = time.monotonic() - started
    record = s.still()
    assert list(record.actual_TCP_pose) == pytest.approx(third, abs=METRE)
    assert took > 1.0  # the durations were kept: 0.6 s + 0.4 s before the linear move
    s.primary.wait_text("trajectory finished: 0")

    # script commands on 50004: their effects show in the RTDE outputs
    driver.script_command("set_payload", mass=1.25, cog=[0.0, 0.01, 0.04])
    driver.script_command("set_tcp_offset", offset=[0.0, 0.0, 0.15, 0.0, 0.0, 0.0])
    driver.script_command("set_tool_voltage", voltage=24.0)
    driver.script_command("zero_ft_sensor")
    driver.script_command(
        "start_force_mode", task_frame=[0.0] * 6, selection_vector=[0, 0, 1, 0, 0, 0],
        wrench=[0, 0, -5, 0, 0, 0], force_type=2, limits=[0.1, 0.1, 0.1, 0.2, 0.2, 0.2],
        damping_factor=0.025, gain_scaling=0.5,
    )  # fmt: skip
    s.primary.wait(lambda w: w.mode.control_mode == FORCE, 5, "FORCE control mode in the Robot State")
    driver.script_command("end_force_mode")
    s.primary.wait(lambda w: w.mode.control_mode == POSITION, 5, "POSITION control mode again")
    driver.script_command("start_tool_contact")
    driver.script_command("end_tool_contact")
    assert driver.tool_contact_result() == "CANCELED"  # ended with no contact: the arm met nothing
    record = s.until(
        lambda r: r.payload == pytest.approx(1.25) and r.tool_output_voltage == 24 and r.tcp_offset[2] > 0.1,
        5, "the script commands' effects",
    )  # fmt: skip
    assert list(record.payload_cog) == pytest.approx([0.0, 0.01, 0.04])
    assert list(record.tcp_offset) == pytest.approx([0.0, 0.0, 0.15, 0.0, 0.0, 0.0])
    flange_to_tcp = kin.forward(model, list(record.actual_q), record.tcp_offset)
    assert list(record.actual_TCP_pose) == pytest.approx(flange_to_tcp, abs=1e-9)
    s.primary.wait(lambda w: sum("script command done" in t for t in w.texts) == 8, 5, "8 commands done")

    # STOPPED ends the program; it closes its sockets
    driver.write_command([0.0] * 6, driver.mode("STOPPED"))
    s.primary.wait_text("external control ended")
    s.primary.wait(lambda w: not w.mode.is_program_running, 5, "the program stopped")
    assert driver.closed_by_robot("reverse")
    assert not s.primary.exceptions


def test_a_flood_of_keepalives_is_read_step_by_step_and_silence_ends_the_program(session: Session) -> None:
    """URCL's script command example writes keepalives in a loop that never sleeps: the program's
    reverse loop reads what arrives until its time slice is used and goes on in the next control
    step, as the controller schedules a thread (no runtime error); when the driver falls silent,
    the read times out after the last record's read_timeout and the program ends itself."""
    s, driver = session, session.driver
    ready_and_run(s)
    burst = driver.reverse_codec.encode(
        "motion_target", {"read_timeout": 0.2, "target": [0.0] * 6, "control_mode": driver.mode("IDLE")}
    )
    driver.robot["reverse"].sendall(burst * 5_000)  # 160 kB at once
    home = s.q()
    goal = [home[0] - 0.1, *home[1:]]
    for _ in range(100):
        driver.write_command(goal, driver.mode("SERVOJ"), read_timeout=0.2)
    s.until(
        lambda r: list(r.actual_q) == pytest.approx(goal, abs=RAD),
        20,
        "the servoj target after the flood",
        False,
    )
    assert not s.primary.exceptions
    s.primary.wait_text("reverse socket timed out: external control ends", 10)
    s.primary.wait(lambda w: not w.mode.is_program_running, 5, "the program stopped")
    assert not s.primary.exceptions


def stream(driver: DriverSide, values: list[float], mode: str, seconds: float) -> None:
    """One record every 2 ms for `seconds`, as the driver's control loop writes them."""
    for _ in range(int(seconds / 0.002)):
        driver.write_command(values, driver.mode(mode), read_timeout=1.0)
        time.sleep(0.002)


@pytest.mark.slow
def test_speed_pose_spline_cancel_and_freedrive_modes_move_the_arm_as_the_driver_asks(
    session: Session,
) -> None:
    s, driver = session, session.driver
    ready_and_run(s)

    # SPEEDJ: joint velocities held while they stream; IDLE stops the arm
    start = s.q()
    stream(driver, [0.2, 0.0, 0.0, 0.0, 0.0, -0.1], "SPEEDJ", 0.5)
    assert list(s.latest().actual_qd) == pytest.approx([0.2, 0.0, 0.0, 0.0, 0.0, -0.1], abs=1e-6)
    record = s.until(lambda r: not any(r.actual_qd), 5, "SPEEDJ stopped by IDLE")
    moved = [b - a for a, b in zip(start, record.actual_q, strict=True)]
    assert moved[0] > 0.05 and moved[5] < -0.025 and moved[1:5] == pytest.approx([0.0] * 4, abs=1e-9)

    # SPEEDL: a tool velocity along z
    pose = s.latest().actual_TCP_pose
    stream(driver, [0.0, 0.0, 0.05, 0.0, 0.0, 0.0], "SPEEDL", 0.5)
    assert s.latest().actual_TCP_speed[2] == pytest.approx(0.05, abs=1e-4)
    record = s.until(lambda r: not any(abs(v) > 1e-9 for v in r.actual_TCP_speed), 5, "SPEEDL stopped")
    assert record.actual_TCP_pose[2] - pose[2] > 0.01
    assert list(record.actual_TCP_pose[:2]) == pytest.approx(list(pose[:2]), abs=1e-4)

    # POSE: a Cartesian target streamed, followed through inverse kinematics
    pose = list(s.latest().actual_TCP_pose)
    goal = [pose[0] + 0.03, pose[1] - 0.02, pose[2], *pose[3:]]
    for i in range(151):
        driver.write_command(straight(pose, goal, min(1.0, i / 100)), driver.mode("POSE"), read_timeout=1.0)
        time.sleep(0.002)
    s.until(lambda r: list(r.actual_TCP_pose) == pytest.approx(goal, abs=METRE), 5, "the POSE target", False)

    # FORWARD, cubic spline points: through a via point at speed, to rest at the end
    q0 = s.q()
    via = [q0[0] + 0.2, q0[1], q0[2] - 0.1, *q0[3:]]
    end = [q0[0] + 0.3, q0[1] + 0.1, q0[2] - 0.1, *q0[3:]]
    late, cut = s.emu.emulator.late_steps, s.emu.emulator.cut_steps
    driver.trajectory_control("START", points=2)
    driver.write_spline_point(via, [0.15, 0.05, 0.0, 0.0, 0.0, 0.0], duration=0.8)
    driver.write_spline_point(end, [0.0] * 6, duration=0.8)
    started = time.monotonic()
    assert driver.trajectory_result() == "SUCCESS"
    assert time.monotonic() - started > 1.2  # 1.6 s of splines
    # a server stalled past `skip_after` (a starved CI machine) skips steps, and by design the arm
    # stands still for them (ControllerModel.tick): each stall may cost one step at the spline's
    # speed (< 0.25 rad/s x 2 ms); with none, the arm ends exactly where the driver asked
    stalls, cuts = s.emu.emulator.late_steps - late, s.emu.emulator.cut_steps - cut
    assert s.q() == pytest.approx(end, abs=RAD + stalls * 0.25 * 0.002), f"{stalls} stalls, {cuts} cut steps"

    # FORWARD, canceled: the result says so and the arm stops short of the target
    q0 = s.q()
    far = [q0[0] - 1.0, *q0[1:]]
    driver.trajectory_control("START", points=2)
    driver.write_point("MOVEJ", far, duration=3.0)
    driver.write_point("MOVEJ", q0, duration=3.0)
    time.sleep(0.5)
    driver.trajectory_control("CANCEL", points=2)
    assert driver.trajectory_result() == "CANCELED"
    record = s.until(lambda r: not any(r.actual_qd), 5, "the arm stopped after CANCEL")
    assert q0[0] - 0.9 < record.actual_q[0] < q0[0] - 0.01

    # FREEDRIVE: the Robot State's control mode is TEACH until it ends
    freedrive = {"read_timeout": 1.0, "unused": [0] * 5, "control_mode": driver.mode("FREEDRIVE")}
    codec = driver.reverse_codec
    driver.robot["reverse"].sendall(codec.encode("freedrive_control", {**freedrive, "freedrive_action": 1}))
    s.primary.wait(lambda w: w.mode.control_mode == TEACH, 5, "TEACH in freedrive")
    driver.robot["reverse"].sendall(codec.encode("freedrive_control", {**freedrive, "freedrive_action": -1}))
    s.primary.wait(lambda w: w.mode.control_mode == POSITION, 5, "POSITION after freedrive")

    driver.write_command([0.0] * 6, driver.mode("STOPPED"))
    s.primary.wait_text("external control ended")
    assert not s.primary.exceptions


def test_after_a_stall_of_the_server_a_speedj_per_step_still_lasts_one_step() -> None:
    """A driver's spline is a speedj of one control step each step (URCL's jointSplineStep). When a
    loaded machine stalls the server and it skips steps, the arm and the program take one step and
    stand still for the rest: each speed lasts its one step, as on a controller, instead of running
    on for the skipped time (a 0.3 rad spline of URCL's went 0.3855 and 0.5012 rad)."""
    model = ControllerModel("5.15.0")
    model.run_script(
        "def spline():\n  i = 0\n  while i < 100:\n    speedj([0.1, 0, 0, 0, 0, 0], 40.0, 0.002)\n"
        "    i = i + 1\n  end\n  stopj(40.0)\nend\n"
    )
    step = 0
    for jump in [1] * 20 + [30] + [1] * 20 + [1000] + [1] * 200:  # stalls of 60 ms and 2 s
        step += jump
        model.tick(step)
    assert model.program is None  # ended
    moved = model.arm.state.q[0] - HOME_Q[0]
    assert moved == pytest.approx(100 * 0.002 * 0.1, abs=2e-4)  # 100 steps at 0.1 rad/s, ramps aside


_SPEEDS = """def speeds():
  start = get_actual_joint_positions()
  i = 0
  while i < 40:
    speedj([0, 0, 0, 0, 0, 0.5], 1000.0, 0.002)
{busy}    i = i + 1
  end
  stopj(1000.0)
  q = get_actual_joint_positions()
  textmsg("wrist 3 moved ", q[5] - start[5])
end
"""
# the same, computing longer than a control step after each speedj
LATE_SPEEDS = _SPEEDS.format(busy="    j = 0\n    while j < 3000:\n      j = j + 1\n    end\n")
SPEEDS = _SPEEDS.format(busy="")


def test_a_held_speed_waits_for_its_thread_when_the_program_is_late(session: Session) -> None:
    """Each speedj asks for one control step of speed; the thread then computes longer than a step
    (as URCL's jointSplineStep can on a loaded machine), so it is preempted before its next speedj.
    The arm waits for it: each speed lasts its step, and wrist 3 moves 40 x 2 ms x 0.5 rad/s. It ran
    on meanwhile, and URCL's spline_example, run after its other examples, hit wrist 3's 2π limit."""
    s = session
    s.primary.wait(lambda w: w.mode is not None, 5, "a Robot State")
    s.primary.send(LATE_SPEEDS)
    s.primary.wait_text("wrist 3 moved", 60)
    moved = float(next(t for t in s.primary.texts if "wrist 3 moved" in t).split()[-1])
    assert moved == pytest.approx(40 * 0.002 * 0.5, abs=5e-4)  # ramps of a=1000 rad/s² aside
    assert not s.primary.exceptions


@pytest.mark.parametrize("decrements", [50, 51])
def test_speedjs_of_one_step_under_the_slider_urcl_leaves_last_what_they_ask_in_sum(
    session: Session, decrements: int
) -> None:
    """URCL's rtde_client example takes the speed slider down by 0.01 a package and leaves it at
    0.49999999999999956 or 0.48999999999999955 (its reset to 1 at exit is racy). A speedj of 2 ms
    then ends 4e-19 s after two steps of the slider's time, or inside the third: each ran three
    steps, and URCL's spline_example, run after that example, went 1.5x as far along its spline, to
    wrist 3's 2π limit. 40 speedjs at 0.5 rad/s move it 40 x 2 ms x 0.5 (the time past each
    speedj's end counts against the next one's)."""
    s, slider = session, 1.0
    for _ in range(decrements):
        slider -= 0.01
    client = RtdeClient("127.0.0.1", s.emu.ports["rtde"]).connect()
    try:
        client.setup_outputs(["timestamp"], 10)
        recipe = client.setup_inputs(["speed_slider_mask", "speed_slider_fraction"])
        client.start()
        client.send(recipe, speed_slider_mask=1, speed_slider_fraction=slider)
        deadline = time.monotonic() + 5
        while s.emu.emulator.model.values["target_speed_fraction"] != slider:
            assert time.monotonic() < deadline, "the slider was not set"
            time.sleep(0.01)
    finally:
        client.close()
    s.primary.wait(lambda w: w.mode is not None, 5, "a Robot State")
    s.primary.send(SPEEDS)
    s.primary.wait_text("wrist 3 moved", 30)
    moved = float(next(t for t in s.primary.texts if "wrist 3 moved" in t).split()[-1])
    assert moved == pytest.approx(40 * 0.002 * 0.5, abs=1e-3)  # the last step and the ramps aside
    assert not s.primary.exceptions
