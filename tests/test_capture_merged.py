"""`capture` of a file merged from two capture points, whose directions are out of order.

mergecap of two one-direction captures (or one host whose NIC queues' clocks differ) sorts
frames by their timestamps: with the controller's clock behind, its setup reply (types and
recipe id only) comes before the client's request (the names); with it ahead, the client's
next request and its input data packages come before the reply they follow. Each
direction's bytes stay in TCP order. Before: the output recipe was lost (exit 1, "needs
--recipe"), the protocol version reply came after the setup request it decides the layout
of (a v2 request read as v1: names garbled, exit 3), and a second setup request took the
names of the first reply. Now the tables are those of the frames in the order they were
sent, byte for byte, and the summary says the same.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Literal

import dpkt
import pyarrow.parquet as pq
import pytest

from rtde_spec import Catalogue, RecipeCodec, build
from tests.capture_files import Conversation, rtde_packages, run_capture

X = ("timestamp", "actual_q", "robot_mode")  # output recipe 1
Y = ("timestamp", "speed_scaling")  # output recipe 2
INS = ("input_int_register_24", "speed_slider_fraction")  # input recipe 1
Frame = tuple[float, bytes, str]  # time, frame, sender ("client" or "server")


def types(names: tuple[str, ...], direction: Literal["input", "output"]) -> list[str]:
    cat = Catalogue.builtin()
    return [cat.get(n, direction).type for n in names]  # type: ignore[union-attr]


VERSION = build("request_protocol_version", protocol_version=2)
VERSION_REPLY = build("request_protocol_version_reply", accepted=True)
SETUP_X = build("setup_outputs_v2", output_frequency=500.0, variable_names=list(X))
SETUP_X_REPLY = build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types(X, "output"))
SETUP_INS_REPLY = build("setup_inputs_reply", input_recipe_id=1, variable_types=types(INS, "input"))
INPUTS = RecipeCodec.for_names(list(INS), "input", Catalogue.builtin())
FIRST_INPUT = INPUTS.encode_package({"input_int_register_24": 5, "speed_slider_fraction": 0.005}, recipe_id=1)


def session(skew: float) -> list[Frame]:
    """A recorder's session in the order it was sent; the server's clock `skew` seconds off."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    sides = ["client", "server"]
    conv.handshake()

    def send(side: str, package: bytes) -> None:
        conv.send(side, package)
        sides.append(side)

    for request, reply in [
        (VERSION, VERSION_REPLY),
        (build("get_urcontrol_version"),
         build("get_urcontrol_version_reply", major=5, minor=12, bugfix=1, build=0)),
        (SETUP_X, SETUP_X_REPLY),
        (build("setup_outputs_v2", output_frequency=125.0, variable_names=list(Y)),
         build("setup_outputs_v2_reply", output_recipe_id=2, variable_types=types(Y, "output"))),
        (build("start"), build("start_reply", accepted=True)),
        (build("setup_inputs", variable_names=list(INS)), SETUP_INS_REPLY),  # input data follow at once
    ]:  # fmt: skip
        send("client", request)
        send("server", reply)
    ys = rtde_packages(30, Y, recipe_id=2)
    for i, package in enumerate(rtde_packages(120, X)):  # the first 40: a run of whole packages
        send("server", package)
        if i >= 40 and i % 4 == 0:
            send("server", ys[i // 4 - 10])
        if i % 10 == 5:
            values = {"input_int_register_24": i, "speed_slider_fraction": i / 1000}
            send("client", INPUTS.encode_package(values, recipe_id=1))
        if i == 60:
            send("server", build("text_message", message="hello", source="test", warning_level=2))
    send("client", build("pause"))
    send("server", build("pause_reply", accepted=True))
    return [
        (t + skew if side == "server" else t, frame, side)
        for (t, frame), side in zip(conv.frames, sides, strict=True)
    ]


def write_frames(path: Path, frames: list[Frame]) -> Path:
    with open(path, "wb") as out:
        writer = dpkt.pcap.Writer(out, linktype=dpkt.pcap.DLT_EN10MB)
        for time, frame, _ in frames:
            writer.writepkt(frame, ts=time)
    return path


def merged(folder: Path, frames: list[Frame], tool: str) -> Path:
    """The two directions captured apart, then merged by time: by mergecap, or as it does."""
    if tool == "sorted":
        return write_frames(folder / "merged.pcap", sorted(frames, key=lambda f: f[0]))
    halves = [
        write_frames(folder / f"{side}.pcap", [f for f in frames if f[2] == side])
        for side in ("client", "server")
    ]
    out = folder / "merged.pcap"
    subprocess.run(["mergecap", "-F", "pcap", "-w", str(out), *map(str, halves)], check=True)
    return out


def tables(out: Path) -> dict[str, object]:
    """Every table file's rows by its folder (file names hold the capture's name), and the listing
    of recipe tables. It lists them in the order their first rows were written: with the clock
    ahead, the client's first input data package is in the file before the controller's first
    output one, and which was first on the wire the capture cannot say; so it is compared as a set."""
    found: dict[str, object] = {
        str(f.parent.relative_to(out)): pq.read_table(f).to_pylist() for f in sorted(out.rglob("*.parquet"))
    }
    (listing,) = out.glob("recipes-*.json")
    found["listing"] = sorted(json.loads(listing.read_text()), key=lambda entry: entry["table"])
    return found


needs_mergecap = pytest.mark.skipif(shutil.which("mergecap") is None, reason="mergecap is not installed")


@pytest.mark.parametrize("tool", ["sorted", pytest.param("mergecap", marks=needs_mergecap)])
@pytest.mark.parametrize("skew", [-0.003, -0.05, 0.003, 0.05])
def test_a_merged_capture_decodes_as_the_frames_in_the_order_they_were_sent(
    tmp_path: Path, skew: float, tool: str
) -> None:
    """Behind (negative skew): every reply before its request; ahead: the client's requests and
    input data before the replies they follow; 50 ms: many packages wait at once."""
    frames = session(skew)
    sent = write_frames(tmp_path / "sent.pcap", frames)
    mixed = merged(tmp_path, frames, tool)
    in_file = [f[1] for f in sorted(frames, key=lambda f: f[0])]

    def at(package: bytes) -> int:
        return next(n for n, frame in enumerate(in_file) if frame.endswith(package))

    if skew < 0:  # the output recipe's reply is in the file before its request
        assert at(SETUP_X_REPLY) < at(SETUP_X)
    else:  # the client's next request before the version reply; with 50 ms, input data before its reply
        assert at(VERSION_REPLY) > at(VERSION) + 1
        assert skew < 0.01 or at(FIRST_INPUT) < at(SETUP_INS_REPLY)
    want = run_capture(str(sent), "-o", str(tmp_path / "want"), cwd=tmp_path)
    got = run_capture(str(mixed), "-o", str(tmp_path / "got"), cwd=tmp_path)
    assert want.returncode == 0, want.stderr
    assert got.returncode == 0, got.stderr
    assert got.stderr.replace(str(mixed), "F") == want.stderr.replace(str(sent), "F")  # no warning, no note
    expected = tables(tmp_path / "want")
    assert tables(tmp_path / "got") == expected
    rows = {key.split("/")[0]: len(value) for key, value in expected.items() if key != "listing"}  # type: ignore[arg-type]
    assert rows == {
        "rtde_outputs_1": 120,
        "rtde_outputs_2": 20,
        "rtde_inputs_1": 12,
        "rtde_setup": 14,
        "rtde_text": 1,
    }
    outputs = expected["rtde_outputs_1/robot=10.0.0.10/date=2023-11-14"]
    times = [row["capture_time"] for row in outputs]  # type: ignore[attr-defined]
    assert times == sorted(times)


def test_a_reply_whose_request_never_comes_needs_recipe_as_before(tmp_path: Path) -> None:
    """Only the controller's direction captured: its setup replies have no request to wait for.
    Exit 1 and the --recipe advice as before; the notes say what waited and why it was let go;
    given the recipe, every data package is decoded."""
    frames = [f for f in session(0.0) if f[2] == "server"]
    path = write_frames(tmp_path / "controller.pcap", frames)
    done = run_capture(str(path), "-o", str(tmp_path / "a"), cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert "needs --recipe" in done.stderr and "give the recipe with --recipe FILE" in done.stderr
    assert "without their request" in done.stderr and "the end of the capture" in done.stderr
    recipe = tmp_path / "outputs.txt"
    recipe.write_text("\n".join(X) + "\n")
    given = run_capture(str(path), "-o", str(tmp_path / "b"), "--recipe", str(recipe), cwd=tmp_path)
    found = tables(tmp_path / "b")
    assert len(found["rtde_outputs_1/robot=10.0.0.10/date=2023-11-14"]) == 120, given.stderr  # type: ignore[arg-type]


def test_past_the_bound_what_waited_is_decoded_and_the_summary_says_so(tmp_path: Path) -> None:
    """A reply whose request is not in the capture holds the controller's packages 5 s of capture
    time, then they go on in order (the rest as runs): every row, noted, exit 0 with --recipe."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    conv.handshake()
    conv.send("server", SETUP_X_REPLY)
    for package in rtde_packages(3000, X):  # 6 s at 500 Hz
        conv.send("server", package)
    path = write_frames(tmp_path / "late.pcap", [(t, f, "") for t, f in conv.frames])
    recipe = tmp_path / "outputs.txt"
    recipe.write_text("\n".join(X) + "\n")
    done = run_capture(str(path), "-o", str(tmp_path / "out"), "--recipe", str(recipe), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (
        "RTDE_CONTROL_PACKAGE_SETUP_OUTPUTS" in done.stderr
        and "after waiting 5 s of capture time" in done.stderr
    )
    rows = tables(tmp_path / "out")["rtde_outputs_1/robot=10.0.0.10/date=2023-11-14"]
    times = [row["capture_time"] for row in rows]  # type: ignore[attr-defined]
    assert len(times) == 3000 and times == sorted(times)


def test_what_waits_is_bounded_and_let_go_in_order_never_dropped() -> None:
    """A reply without its request holds the controller's packages behind it; past HOLD_PACKAGES,
    HOLD_BYTES or HOLD_SECONDS the oldest goes on without it (noted), in order."""
    from rtde_spec.capture.protocols.rtde_order import HOLD_BYTES, HOLD_PACKAGES, HOLD_SECONDS, CausalOrder

    reply = build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types(X, "output"))
    data = rtde_packages(HOLD_PACKAGES + 100, X)
    for bound, step, size in [("packages", 0.0, 64), ("capture time", 0.01, 64), ("bytes", 0.0, 1000)]:
        order = CausalOrder()
        out = list(order.take("controller", reply, 0.0))
        packages = [(p + bytes(size - len(p)))[:size] for p in data]  # the bytes bound: larger packages
        for n, package in enumerate(packages):
            out += order.take("controller", package, n * step)
            assert order.count <= HOLD_PACKAGES and order.held_bytes <= HOLD_BYTES + size
            if bound == "capture time" and order.count:
                assert n * step - order.held["controller"][0][2] <= HOLD_SECONDS
        out += order.finish()
        assert [p for _, p, _ in out] == [reply, *packages]  # all, in order
        assert order.count == 0 and order.held_bytes == 0
        (note,) = order.notes()
        assert "SETUP_OUTPUTS" in note and "without their request" in note and bound in note, (bound, note)


def test_a_client_request_waits_for_the_answer_to_the_one_before() -> None:
    """Two output setups sent before either reply is in view pair with their own replies (the
    session keeps one request's names per direction until its reply)."""
    from rtde_spec.capture.protocols.rtde_order import CausalOrder

    first = build("setup_outputs_v2", output_frequency=500.0, variable_names=list(X))
    second = build("setup_outputs_v2", output_frequency=125.0, variable_names=list(Y))
    order = CausalOrder()
    out = [*order.take("client", first, 0.0), *order.take("client", second, 0.001)]
    assert [p for _, p, _ in out] == [first]
    reply = build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=types(X, "output"))
    out = list(order.take("controller", reply, 0.002))
    assert [p for _, p, _ in out] == [reply, second]
    assert not order.notes()


def test_the_clients_packages_wait_for_the_version_its_request_sets() -> None:
    """The layout of what the client sends after a version request is the version's it gets."""
    from rtde_spec.capture.protocols.rtde_order import CausalOrder

    text = build("text_message", message="hi", source="client", warning_level=2)
    order = CausalOrder()
    out = [*order.take("client", VERSION, 0.0), *order.take("client", text, 0.001)]
    assert [p for _, p, _ in out] == [VERSION]
    assert [p for _, p, _ in order.take("controller", VERSION_REPLY, 0.002)] == [VERSION_REPLY, text]
    assert not order.count and not order.notes()
