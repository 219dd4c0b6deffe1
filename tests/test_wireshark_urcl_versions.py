"""The generated dissector reads URCL trajectory points (port 50003) in the layout their session
uses: the one the program the driver sent the same robot on 50002 earlier in the capture names
(by the spec's detect lines), else the newest, or the one the `Trajectory point layout`
preference names. Each record shows the layout and why (`urcl_trajectory.layout`,
`urcl_trajectory.layout_reason`); an older layout's fields are `urcl_trajectory.<layout>.<field>`,
decoded with its own scales (durations in milliseconds on the wire, seconds shown).

The sessions are the pcaps tests/test_capture_urcl_versions.py builds for capture.
"""

from __future__ import annotations

import subprocess
from pathlib import Path
from typing import Any

import pytest

from rtde_spec.cli.wireshark_cmd import dissector_path

from .capture_files import Conversation, write
from .test_capture_urcl_versions import (
    NEWEST_LINES,
    POSE,
    QD,
    V0_LINES,
    V1_LINES,
    V2_LINES,
    Q,
    newest_spline,
    packed,
    program,
    reverse_start,
    script_sender,
    session,
    trajectory,
    v0_points,
    v1_points,
)
from .test_wireshark import TSHARK

FROM_PROGRAM = "from the program on 50002"
T0 = 1_700_000_000.0


def decoded(path: Path, *names: str, options: tuple[str, ...] = (), passes: int = 1) -> dict[str, list[str]]:
    """Every value of `urcl_trajectory.<name>` over the capture's trajectory points, in order."""
    args = [str(TSHARK), "-X", f"lua_script:{dissector_path()}", *options, *(["-2"] if passes == 2 else [])]
    args += ["-r", str(path), "-Y", "urcl_trajectory.layout", "-T", "fields", "-E", "aggregator=;"]
    for name in names:
        args += ["-e", f"urcl_trajectory.{name}"]
    result = subprocess.run(args, capture_output=True, text=True, check=True)
    assert "Lua" not in result.stderr or "error" not in result.stderr.lower(), result.stderr
    out: dict[str, list[str]] = {name: [] for name in names}
    for line in result.stdout.splitlines():
        for name, cell in zip(names, line.split("\t"), strict=True):
            out[name] += cell.split(";") if cell else []
    return out


def numbers(cells: list[str]) -> list[float]:
    return [float(c) for c in cells]


def approx(value: list[float]) -> Any:
    """Equal to what the wire keeps: 1e-6 steps (Q's 3.1415926 arrives as 3.141593)."""
    return pytest.approx(value, abs=1e-6)


MOVEJ_MS = {"target": Q, "velocity_or_via": [1.05] * 6, "acceleration_or_movec": [1.4] * 6,
            "duration": 2.0, "blend_radius": 0.05, "motion_type": 0}  # fmt: skip
SPLINE_MS = {"positions": Q, "velocities": QD, "accelerations": QD, "duration": 0.25, "spline_type": 2,
             "motion_type": 51}  # fmt: skip
MOVEJ_US = {"target": Q, "via_or_q_near": [0.0] * 6, "velocity": 1.05, "acceleration": 1.4,
            "mode_or_has_q_near": 0.0, "unused": [0, 0, 0], "duration": 2.0, "blend_radius": 0.05,
            "motion_type": 0}  # fmt: skip


def motion_type_ms_points() -> list[bytes]:
    return [
        packed("motion_type_ms", "motion_primitive", MOVEJ_MS),
        packed("motion_type_ms", "spline_point", SPLINE_MS),
    ]


def newest_points() -> list[bytes]:
    return [packed(None, "motion_primitive", MOVEJ_US), newest_spline()]


# layout -> (a program with its detect lines, records in it, field prefix, the values they carry)
LAYOUTS: dict[str, tuple[bytes, list[bytes], str, dict[str, list[Any]]]] = {
    "motion_type_us": (
        program(NEWEST_LINES, 1_000_000), newest_points(), "",
        {"variant": ["motion_primitive", "spline_point"], "duration": [2.0, 0.25], "velocity": [1.05],
         "acceleration": [1.4], "blend_radius": [0.05], "target": [Q], "positions": [Q], "velocities": [QD],
         "spline_type": [1], "motion_type": [0, 51]},
    ),
    "motion_type_ms": (
        program(V2_LINES, 1000), motion_type_ms_points(), "motion_type_ms.",
        {"variant": ["motion_primitive", "spline_point"], "duration": [2.0, 0.25], "blend_radius": [0.05],
         "target": [Q], "velocity_or_via": [[1.05] * 6], "acceleration_or_movec": [[1.4] * 6],
         "positions": [Q], "velocities": [QD], "spline_type": [2], "motion_type": [0, 51]},
    ),
    "point_type_21": (
        program(V1_LINES, 1000), v1_points(), "point_type_21.",
        {"variant": ["point", "point"], "duration": [0.5, 2.0], "point_type": [2, 0], "positions": [Q, Q],
         "velocities": [QD, QD], "accelerations": [[-x for x in QD]] * 2, "blend_radius": [0.0, 0.0]},
    ),
    "cartesian_flag_9": (
        program(V0_LINES, 1000), v0_points(), "cartesian_flag_9.",
        {"variant": ["point"] * 3, "duration": [2.0, 1.25, 0.5], "blend_radius": [0.05, 0.0, 0.0],
         "positions": [Q, POSE, Q], "cartesian": [0, 1, 0]},
    ),
}  # fmt: skip
OTHER = {"motion_type_us": "cartesian_flag_9", "motion_type_ms": "point_type_21",
         "point_type_21": "motion_type_us", "cartesian_flag_9": "motion_type_ms"}  # fmt: skip


def assert_values(path: Path, layout: str, why: str, options: tuple[str, ...] = ()) -> None:
    """The records of `path` read in `layout` for reason `why`, every value LAYOUTS gives."""
    _, records, prefix, values = LAYOUTS[layout]
    keys = [k if k == "variant" else prefix + k for k in values]
    got = decoded(path, "layout", "layout_reason", *keys, options=options)
    assert got["layout"] == [layout] * len(records)
    assert got["layout_reason"] == [why] * len(records)
    for key, (name, want) in zip(keys, values.items(), strict=True):
        if name == "variant":
            assert got[key] == want
        elif isinstance(want[0], (list, tuple)):
            assert numbers(got[key]) == approx([x for w in want for x in w]), key
        else:
            assert numbers(got[key]) == approx(want), key


@pytest.mark.parametrize("layout", list(LAYOUTS))
def test_each_layout_from_the_program_on_50002(tmp_path: Path, layout: str) -> None:
    text, records, _, _ = LAYOUTS[layout]
    assert_values(session(tmp_path, text, records), layout, FROM_PROGRAM)


@pytest.mark.parametrize("layout", list(LAYOUTS))
def test_the_preference_overrides_the_program(tmp_path: Path, layout: str) -> None:
    """The program names another layout; the preference's is read, and it says so."""
    _, records, _, _ = LAYOUTS[layout]
    path = session(tmp_path, LAYOUTS[OTHER[layout]][0], records)
    assert_values(path, layout, "preference", options=("-o", f"urcl_trajectory.layout:{layout}"))


def test_without_a_program_the_newest_and_it_says_so(tmp_path: Path) -> None:
    path = session(tmp_path, None, newest_points())
    assert_values(path, "motion_type_us", "no program seen: newest")
    assert_values(
        path, "motion_type_us", "no program seen: newest", options=("-o", "urcl_trajectory.layout:auto")
    )


def test_a_program_that_sets_an_unknown_multiplier_names_none(tmp_path: Path) -> None:
    """The capture's rule: a program setting a MULT_ the detect lines do not name matches no layout."""
    text = program(NEWEST_LINES, 1_000_000).replace(b"MULT_time", b"MULT_velacc = 100000000\nMULT_time")
    path = session(tmp_path, text, newest_points())
    assert_values(path, "motion_type_us", "the program on 50002 names none: newest")


def test_36_byte_records_across_segment_boundaries(tmp_path: Path) -> None:
    """cartesian_flag_9 frames 36-byte records, wherever the segments split them."""
    data = b"".join(v0_points())
    convs = [script_sender(LAYOUTS["cartesian_flag_9"][0], T0), reverse_start(3, T0 + 1.5)]
    path = write(tmp_path / "split.pcap", [*convs, trajectory([data[:50], data[50:]], T0 + 1)])
    got = decoded(path, "layout", "cartesian_flag_9.duration", "cartesian_flag_9.cartesian")
    assert got["layout"] == ["cartesian_flag_9"] * 3
    assert numbers(got["cartesian_flag_9.duration"]) == approx([2.0, 1.25, 0.5])
    assert got["cartesian_flag_9.cartesian"] == ["0", "1", "0"]


def test_a_new_program_decides_for_later_points_only(tmp_path: Path) -> None:
    """The robot's program restarts with another driver: points before read the first program's
    layout, points after the second's, also when the dissector makes two passes."""
    second = Conversation(("192.168.56.101", 40013), ("192.168.56.1", 50003), time=T0 + 11)
    second.handshake()
    for record in v1_points():
        second.send("server", record, dt=0.001)
    convs = [
        script_sender(LAYOUTS["cartesian_flag_9"][0], T0),
        trajectory(v0_points(), T0 + 1),
        script_sender(LAYOUTS["point_type_21"][0], T0 + 10, port=40012),
        second,
    ]
    path = write(tmp_path / "restart.pcap", convs)
    for passes in (1, 2):
        got = decoded(path, "layout", "layout_reason", "cartesian_flag_9.duration", "point_type_21.duration",
                      passes=passes)  # fmt: skip
        assert got["layout"] == ["cartesian_flag_9"] * 3 + ["point_type_21"] * 2
        assert got["layout_reason"] == [FROM_PROGRAM] * 5
        assert numbers(got["cartesian_flag_9.duration"]) == approx([2.0, 1.25, 0.5])
        assert numbers(got["point_type_21.duration"]) == approx([0.5, 2.0])


def test_each_robot_reads_its_own_program(tmp_path: Path) -> None:
    other = "192.168.56.102"
    new = Conversation((other, 40002), ("192.168.56.1", 50002), time=T0 + 0.2)
    new.handshake()
    new.send("client", b"request_program\n")
    new.send("server", LAYOUTS["point_type_21"][0], dt=0.0005)
    points = Conversation((other, 40003), ("192.168.56.1", 50003), time=T0 + 1.2)
    points.handshake()
    for record in v1_points():
        points.send("server", record, dt=0.001)
    convs = [script_sender(LAYOUTS["cartesian_flag_9"][0], T0), new, trajectory(v0_points(), T0 + 1), points]
    got = decoded(write(tmp_path / "two.pcap", convs), "layout", "point_type_21.point_type")
    assert got["layout"] == ["cartesian_flag_9"] * 3 + ["point_type_21"] * 2
    assert got["point_type_21.point_type"] == ["2", "0"]
