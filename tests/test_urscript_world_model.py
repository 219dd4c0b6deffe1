"""The world model PolyScope X programs use: named frames in a tree, the robot's four (world, base,
flange, tcp) and a program's own, composed as rigid transforms and kept by the controller between
programs until reset_world_model().

The programs here are written for these tests in the shapes of real ones (not copied from them):
the application script PolyScope X 10.14 generates for a URSim UR7e in UR's client library
(UniversalRobots/Universal_Robots_Client_Library, tests/resources/dockerursim/programs/polyscopex/
10.14.0/ur7e/0/application.final.script, and the same script in tests/resources/upload_prog.urpx),
the one in UR's ROS 2 driver's ur_robot_driver/test/test_program.urpx (reset_world_model, base
read with get_frame_parent and get_pose and put back with move_frame, set_tcp with the TCP's name,
waypoints as structs of p, frame and q, smart skills using rotvec2rpy, rpy2rotvec and size), and
the program nodes of UR's PolyScope X SDK (Move moves to convert_pose(wp.p, wp.frame, "base"),
Tool Force gives force_mode get_pose(frame)). Every expected pose is computed here with numpy,
from rotation vectors by Rodrigues' formula, not with the emulator's kinematics module.
"""

from __future__ import annotations

import math
import textwrap
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from rtde_spec import EmulatorConfig, EmulatorThread, PrimaryClient, RtdeClient
from rtde_spec.emulator.controller.model import ControllerModel

POLYSCOPE_X = "10.14.0"


def matrix(pose: Sequence[float]) -> np.ndarray:
    """A pose [x, y, z, rx, ry, rz] as a 4x4 transform (Rodrigues' formula)."""
    vector = np.asarray(pose[3:], dtype=float)
    angle = float(np.linalg.norm(vector))
    turn = np.eye(3)
    if angle > 1e-15:
        k = vector / angle
        skew = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        turn = np.eye(3) + math.sin(angle) * skew + (1 - math.cos(angle)) * skew @ skew
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = turn, pose[:3]
    return out


def rigid_inverse(m: np.ndarray) -> np.ndarray:
    return np.linalg.inv(m)


def same(pose: Sequence[float], expected: np.ndarray) -> None:
    """`pose` (as a program got it) is the transform `expected`."""
    assert matrix(pose) == pytest.approx(expected, abs=1e-9)


def run(
    script: str, model: ControllerModel | None = None, steps: int = 4000
) -> tuple[ControllerModel, list[Any]]:
    """`script` on a PolyScope X controller until it reaches its closing sleep (or ends)."""
    model = model or ControllerModel(POLYSCOPE_X)
    model.run_script(script)
    events = model.drain_events()
    for _ in range(steps):
        program = model.program
        if program is None or program.globals.get("done"):
            break
        model.tick(model.step + 1)
        events += model.drain_events()
    return model, events


def faults(events: list[Any]) -> list[tuple[str, int]]:
    return [(e.text, e.line) for e in events if e.kind == "runtime_exception"]


def results(model: ControllerModel) -> dict[str, Any]:
    assert model.program is not None, "the program ended before its results were read"
    return model.program.globals


# --- poses compose as rigid transforms -------------------------------------------------------------

TABLE = [0.4, -0.2, 0.05, 0.0, 0.0, 0.5]
FIXTURE = [0.1, 0.02, 0.03, 0.1, -0.2, 0.3]  # in the table's coordinates
TABLE_MOVED = [0.5, 0.1, 0.0, 0.0, 0.3, -0.4]
POINT = [0.01, 0.02, 0.03, 0.3, 0.2, 0.1]  # in the fixture's coordinates
BASE_MOVED = [0.0, 0.0, 0.2, 0.0, 0.0, 1.0]  # in the world's


def p(values: Sequence[float]) -> str:
    return "p[" + ", ".join(repr(v) for v in values) + "]"


def test_frames_compose_and_an_attached_frame_moves_with_its_parent() -> None:
    model, events = run(
        "reset_world_model()\n"
        f'add_frame("table", {p(TABLE)})\n'
        f'add_frame("fixture", {p(FIXTURE)}, "table")\n'
        'fixture_parent_added = get_frame_parent("fixture")\n'
        'attach_frame("fixture", "table")\n'
        f'move_frame("table", {p(TABLE_MOVED)})\n'
        'fixture_in_base = get_pose("fixture")\n'
        'fixture_in_table = get_pose("fixture", "table")\n'
        f'point_in_base = convert_pose({p(POINT)}, "fixture", "base")\n'
        'fixture_parent = get_frame_parent("fixture")\n'
        'table_parent = get_frame_parent("table")\n'
        f'move_frame("base", {p(BASE_MOVED)}, "world")\n'
        'table_in_base = get_pose("table")\n'
        'table_in_world = get_pose("table", "world")\n'
        'base_in_world = get_pose("base", "world")\n'
        "done = True\nsleep(60)\n"
    )
    assert faults(events) == []
    got = results(model)
    table, fixture, point, base = matrix(TABLE_MOVED), matrix(FIXTURE), matrix(POINT), matrix(BASE_MOVED)
    same(got["fixture_in_base"], table @ fixture)
    same(got["fixture_in_table"], fixture)
    same(got["point_in_base"], table @ fixture @ point)
    assert (got["fixture_parent_added"], got["fixture_parent"], got["table_parent"]) == (
        "world",
        "table",
        "world",
    )
    same(got["table_in_world"], table)  # the base was at the world origin when the table moved
    same(got["table_in_base"], rigid_inverse(base) @ table)
    same(got["base_in_world"], base)


def test_the_flange_and_tcp_frames_are_where_the_arm_is_and_a_frame_on_the_tool_follows_it() -> None:
    tcp_offset = [0.0, 0.0, 0.15, 0.0, 0.0, 0.3]
    held_in_tcp = [0.05, 0.0, 0.2, 0.0, 0.4, 0.0]
    station = [0.3, 0.3, 0.1, 0.0, 0.0, 0.0]
    model, events = run(
        f'set_tcp({p(tcp_offset)}, "Gripper")\n'
        f'add_frame("held", {p(held_in_tcp)}, "tcp")\n'
        'attach_frame("held", "tcp")\n'
        f'add_frame("station", {p(station)})\n'
        'held_before = get_pose("held")\n'
        "movel(pose_trans(get_actual_tcp_pose(), p[0.05, -0.04, 0.03, 0.1, 0.0, 0.2]), a=1.2, v=0.25)\n"
        'held = get_pose("held")\n'
        'held_offset = get_pose("held", "tcp")\n'
        'station_now = get_pose("station")\n'
        'tcp = get_pose("tcp")\n'
        'flange = get_pose("flange")\n'
        'tcp_in_flange = get_pose("tcp", "flange")\n'
        "tool = get_actual_tcp_pose()\n"
        "done = True\nsleep(60)\n"
    )
    assert faults(events) == []
    got = results(model)
    tool = matrix(model.values["actual_TCP_pose"])
    same(got["tool"], tool)  # the arm stands where the program read it
    same(got["tcp"], tool)
    same(got["tcp_in_flange"], matrix(tcp_offset))
    same(got["flange"], tool @ rigid_inverse(matrix(tcp_offset)))
    same(got["held"], tool @ matrix(held_in_tcp))  # moved with the tool
    same(got["held_offset"], matrix(held_in_tcp))
    same(got["station_now"], matrix(station))  # attached to the world: stayed
    assert np.linalg.norm(matrix(got["held"])[:3, 3] - matrix(got["held_before"])[:3, 3]) > 0.03


def test_deleting_a_frame_leaves_what_hung_from_it_where_it_stands() -> None:
    model, events = run(
        f'add_frame("a", {p(TABLE)})\n'
        f'add_frame("b", {p(FIXTURE)}, "a")\n'
        'attach_frame("b", "a")\n'
        'attach_frame("base", "a")\n'  # a robot on a rail: its base hangs from a frame too
        'b_before = get_pose("b", "world")\n'
        'base_before = get_pose("base", "world")\n'
        'delete_frame("a")\n'
        'b_after = get_pose("b", "world")\n'
        'b_parent = get_frame_parent("b")\n'
        'base_parent = get_frame_parent("base")\n'
        "delete_all_frames()\n"
        'base_after = get_pose("base", "world")\n'
        "done = True\nsleep(60)\n"
    )
    assert faults(events) == []
    got = results(model)
    same(got["b_after"], matrix(got["b_before"]))
    same(got["base_after"], matrix(got["base_before"]))  # delete_all_frames does not move the base
    assert (got["b_parent"], got["base_parent"]) == ("world", "world")
    assert set(model.world_model.frames) == {"base"}  # type: ignore[attr-defined]


def test_the_world_model_outlives_a_program_until_reset_world_model() -> None:
    model, events = run(f'add_frame("station", {p(TABLE)})\nmove_frame("base", {p(BASE_MOVED)}, "world")\n')
    assert faults(events) == [] and model.program is None
    model, events = run('kept = get_pose("station", "world")\ndone = True\nsleep(60)\n', model)
    assert faults(events) == []
    same(results(model)["kept"], matrix(TABLE))
    model.stop_program()
    model, events = run(
        'reset_world_model()\nbase = get_pose("base", "world")\ndone = True\nsleep(60)\n', model
    )
    assert faults(events) == []
    same(results(model)["base"], np.eye(4))
    model.stop_program()
    _, events = run('x = get_pose("station")\n', model)
    assert faults(events) == [
        ("get_pose: no frame named 'station' in the world model (it has world, base, flange, tcp)", 1)
    ]


@pytest.mark.parametrize(
    ("lines", "problem"),
    [
        ('x = get_pose("nope")', "get_pose: no frame named 'nope' in the world model"),
        ('x = get_pose("base", "nope")', "get_pose: no frame named 'nope'"),
        (
            'add_frame("tcp", p[0, 0, 0, 0, 0, 0])',
            "add_frame: a frame named 'tcp' exists already (world, base, flange",
        ),
        (
            'add_frame("a", p[0, 0, 0, 0, 0, 0])\nadd_frame("a", p[0, 0, 0, 0, 0, 0])',
            "add_frame: a frame named 'a' exists already",
        ),
        ("add_frame(3, p[0, 0, 0, 0, 0, 0])", "add_frame: name must be a frame's name (a text), not int"),
        ('add_frame("a", [0, 0, 0])', "add_frame: pose must be six numbers"),
        ('attach_frame("tcp", "base")', "attach_frame: 'tcp' cannot be attached elsewhere"),
        ('attach_frame("base", "base")', "attach_frame: 'base' cannot be attached to itself"),
        (
            'add_frame("a", p[0, 0, 0, 0, 0, 0])\nadd_frame("b", p[0, 0, 0, 0, 0, 0])\n'
            'attach_frame("b", "a")\nattach_frame("a", "b")',
            "attach_frame: attaching 'a' to 'b' would close a chain (b -> a already)",
        ),
        (
            'add_frame("a", p[0, 0, 0, 0, 0, 0])\nattach_frame("a", "tcp")\nattach_frame("base", "a")',
            "attach_frame: attaching 'base' to 'a' would close a chain (a -> tcp -> flange -> base already)",
        ),
        (
            'delete_frame("base")',
            "delete_frame: 'base' is one of the robot's frames (world, base, flange, tcp)",
        ),
        ('delete_frame("nope")', "delete_frame: no frame named 'nope'"),
        ('move_frame("flange", p[0, 0, 0, 0, 0, 0])', "move_frame: 'flange' cannot be moved"),
        ('move_frame("world", p[0, 0, 0, 0, 0, 0])', "move_frame: 'world' cannot be moved"),
        ('x = get_frame_parent("world")', "get_frame_parent: 'world' is the root of the world model"),
        ('x = convert_pose(p[0, 0, 0, 0, 0, 0], "base", "nope")', "convert_pose: no frame named 'nope'"),
    ],
)
def test_what_the_world_model_refuses_is_a_runtime_exception_at_its_line(lines: str, problem: str) -> None:
    _, events = run("reset_world_model()\n" + lines + "\n")
    ((text, line),) = faults(events)
    assert text.startswith(problem) and line == lines.count("\n") + 2


def test_a_program_may_add_only_so_many_frames() -> None:
    from rtde_spec.emulator.urscript.world_model import MAX_FRAMES

    _, events = run(
        'reset_world_model()\ni = 0\nwhile i <= 2000:\n  add_frame(str_cat("f", i), p[0, 0, 0, 0, 0, 0])\n'
        "  i = i + 1\n  if i % 100 == 0:\n    sync()\n  end\nend\n"
    )
    ((text, line),) = faults(events)
    assert text == f"add_frame: the world model holds at most {MAX_FRAMES} frames of programs" and line == 4


def test_a_chain_of_frames_is_at_most_so_deep() -> None:
    from rtde_spec.emulator.urscript.world_model import MAX_DEPTH

    _, events = run(
        'reset_world_model()\nadd_frame("f0", p[0, 0, 0, 0, 0, 0])\ni = 1\nwhile i < 100:\n'
        '  add_frame(str_cat("f", i), p[0, 0, 0.01, 0, 0, 0], str_cat("f", i - 1))\n'
        '  attach_frame(str_cat("f", i), str_cat("f", i - 1))\n  i = i + 1\nend\n'
    )
    ((text, line),) = faults(events)
    assert text == (
        f"attach_frame: attaching 'f{MAX_DEPTH - 1}' to 'f{MAX_DEPTH - 2}' would chain {MAX_DEPTH + 1} "
        f"frames (at most {MAX_DEPTH})"
    )
    assert line == 6


# --- the maths PolyScope X's smart skills call ---------------------------------------------------------


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rz(yaw) Ry(pitch) Rx(roll), as the Script Manual defines RPY."""
    cr, sr, cp, sp, cy, sy = (f(a) for a in (roll, pitch, yaw) for f in (math.cos, math.sin))
    x = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    y = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    z = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return z @ y @ x


def test_rpy_conversions_give_the_manuals_examples_and_invert_each_other() -> None:
    model, events = run(
        "a = rotvec2rpy([3.14, 1.57, 0])\nb = rpy2rotvec([3.14, 1.57, 0])\n"
        "c = rpy2rotvec([0.3, -0.7, 2.5])\nd = rotvec2rpy(c)\ne = rotvec2rpy([0, 0, 0])\n"
        'f = size([[1, 2, 3], [4, 5, 6]])\ng = size([1, 2, 3, 4])\ns = size("here I am")\n'
        "h = size([p[0, 0, 0, 0, 0, 0], p[1, 1, 1, 0, 0, 0]])\n"
        "done = True\nsleep(60)\n"
    )
    assert faults(events) == []
    got = results(model)
    assert got["a"] == pytest.approx([-2.80856, -0.16202, 0.9], abs=1e-5)  # rotvec2rpy's example
    assert got["b"] == pytest.approx([2.22153, 0.00177, -2.21976], abs=1e-5)  # rpy2rotvec's example
    assert matrix([0, 0, 0, *got["c"]])[:3, :3] == pytest.approx(rpy_matrix(0.3, -0.7, 2.5), abs=1e-12)
    assert got["d"] == pytest.approx([0.3, -0.7, 2.5], abs=1e-12)
    assert got["e"] == [0.0, 0.0, 0.0]
    assert (got["f"], got["g"], got["h"]) == ([2, 3], 4, [2, 6])  # a matrix's shape, an array's length
    assert got["s"] == 9  # the Script Directory's size("here I am")


@pytest.mark.parametrize("version", ["3.15.8", "5.15.0", POLYSCOPE_X])
def test_an_int_s_32_bits_go_to_a_list_of_bools_and_back(version: str) -> None:
    """The Script Directory's urmath: index 0 the least significant bit, signed 32-bit ints (UR's
    "Modbus server bit access" article reads a port register's bits so)."""
    model, events = run(
        "a = integer_to_binary_list(57)\nb = integer_to_binary_list(-57)\n"
        "c = binary_list_to_integer([True, False, False, True])\nd = binary_list_to_integer(b)\n"
        f"e = binary_list_to_integer([])\nf = binary_list_to_integer([{', '.join(['True'] * 32)}, False])\n"
        "done = True\nsleep(60)\n",
        ControllerModel(version),
    )
    assert faults(events) == []
    got = results(model)
    assert got["a"] == [True, False, False, True, True, True] + [False] * 26  # 57 = 0b111001
    assert got["b"] == [True, True, True, False, False, False] + [True] * 26
    assert (got["c"], got["d"], got["e"], got["f"]) == (9, -57, 0, -1)  # past 32 bools: the first 32


def test_the_world_model_is_polyscope_xs_and_polyscope_x_keeps_the_e_series_functions() -> None:
    for version in ("5.22.0", "3.15.8"):
        _, events = run("reset_world_model()\n", ControllerModel(version))
        assert faults(events) == [("compile_error_name_not_found:reset_world_model:", 1)]
    _, events = run(
        "m = get_target_payload()\nx = time()\nq = rpy2rotvec([0, 0, 1])\n", ControllerModel("10.0.0")
    )
    assert faults(events) == []  # e-Series functions (5.10, 5.22) are PolyScope X's from 10.0


# --- a whole PolyScope X program over the ports -----------------------------------------------------

HOME_Q = [0.0, -1.5707963, 1.5707963, -1.5707963, -1.5707963, 0.0]
STATION = [0.35, 0.25, 0.12, 0.0, 0.0, 0.4]  # a user frame, in Base
WAYPOINT = [0.02, -0.03, 0.15, math.pi, 0.0, 0.0]  # a waypoint taught in the station frame
PART = [0.0, 0.0, 0.05, 0.0, 0.0, 0.0]  # a part held 5 cm beyond the TCP

APPLICATION = f"""set_safety_mode_transition_hardness(1)
reset_world_model()
set_input_actions_to_default()
set_tool_voltage(0)
set_gravity([0, 0, 9.82])
local existingBaseParent = get_frame_parent("base")
local basePose = get_pose("base", existingBaseParent)
basePose[3] = 0
basePose[4] = 0
basePose[5] = 0
move_frame("base", basePose, existingBaseParent)
global base = "base"
global tcp = "tcp"
global world = "world"
global flange = "flange"
add_frame("station", {p(STATION)}, base)
set_target_payload(0.5, [0, 0, 0.05], [0, 0, 0, 0, 0, 0])
set_tcp(p[0, 0, 0.1, 0, 0, 0], "Gripper_tip")
global PI = acos(-1)
def ur_tool_z_down(frame_id = "world"):
  local frame = get_pose(frame_id)
  local rpy = rotvec2rpy([frame[3], frame[4], frame[5]])
  return rpy2rotvec([PI, 0, rpy[2]])
end
global Home = struct(p=p[0, 0, 0, 0, 0, 0], frame="base", q={HOME_Q})
global Pick = struct(p={p(WAYPOINT)}, frame="station", q={HOME_Q})
"""
PROGRAM = """$ 1 "ur-program"
$ 2 "ur-modules"
$ 3 "ur-functions"
$ 4 "ur-before-start"
$ 5 "ur-code"
$ 6 "ur-move"
movej(Home.q, a=1.4, v=1.05)
$ 7 "ur-move"
movej(get_inverse_kin(convert_pose(Pick.p, Pick.frame, "base"), qnear=Pick.q), a=1.4, v=1.05)
add_frame("part", p[0, 0, 0.05, 0, 0, 0], tcp)
attach_frame("part", tcp)
$ 8 "ur-move"
movel(pose_trans(convert_pose(Pick.p, Pick.frame, "base"), p[0, 0, -0.1, 0, 0, 0]), a=1.2, v=0.25)
$ 9 "ur-set"
local part = get_pose("part", "station")
local down = ur_tool_z_down("station")
write_output_float_register(24, part[0])
write_output_float_register(25, part[1])
write_output_float_register(26, part[2])
write_output_float_register(27, down[0])
write_output_float_register(28, down[1])
write_output_boolean_register(64, True)
$ 10 "ur-wait"
sleep(60)
"""


def test_a_polyscope_x_program_runs_over_the_ports_and_its_frames_agree_with_numpy() -> None:
    config = EmulatorConfig(
        controller=POLYSCOPE_X, rtde_port=0, primary_port=None, secondary_port=0,
        dashboard_port=None, realtime_port=None,
    )  # fmt: skip
    fields = [
        "actual_TCP_pose",
        "output_bit_register_64",
        *(f"output_double_register_{n}" for n in range(24, 29)),
    ]
    with EmulatorThread(config) as emu, RtdeClient("127.0.0.1", emu.ports["rtde"]) as rtde:
        rtde.setup_outputs(fields, 50)
        rtde.start()
        with PrimaryClient("127.0.0.1", emu.ports["secondary"]) as client:
            # a program sent to a port runs once its `end` has come (loose lines run one by one)
            client.send_script(
                "def polyscope_x_program():\n" + textwrap.indent(APPLICATION + PROGRAM, "  ") + "end\n"
            )
        deadline = time.monotonic() + 30
        while not (record := rtde.receive(2)).output_bit_register_64:
            assert time.monotonic() < deadline, "the program never reached its end: " + repr(
                emu.model.drain_events()
            )
        tool = matrix(record.actual_TCP_pose)
        part = [getattr(record, f"output_double_register_{n}") for n in range(24, 29)]
    station, pick = matrix(STATION), matrix(WAYPOINT)
    # the last move: 10 cm back along the waypoint's z, the part 5 cm beyond the TCP
    assert tool == pytest.approx(station @ pick @ matrix([0, 0, -0.1, 0, 0, 0]), abs=1e-6)
    expected_part = rigid_inverse(station) @ tool @ matrix(PART)
    assert part[:3] == pytest.approx(expected_part[:3, 3], abs=1e-6)
    down = matrix([0, 0, 0, *part[3:5], 0.0])[:3, :3]  # rx, ry of rpy2rotvec([pi, 0, yaw]); rz is 0
    assert down @ np.array([0, 0, 1]) == pytest.approx([0, 0, -1], abs=1e-9)
