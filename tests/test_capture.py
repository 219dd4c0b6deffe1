"""Captures made here (dpkt frame by frame) with every edge case, decoded into tables."""

from __future__ import annotations

import json
import os
import sys
import threading
from pathlib import Path

import pyarrow.dataset as ds
import pytest

from rtde_spec import RecipeCodec, build
from rtde_spec.capture.decoder import CaptureInterrupted, capture_tables, decode_to_directory

from .capture_files import Conversation, write
from .test_cli import cli

NAMES = ["timestamp", "actual_q", "robot_mode"]
CODEC = RecipeCodec.for_names(NAMES, "output")
INPUTS = ["input_int_register_24", "speed_slider_fraction"]


def dataset(folder: Path):  # type: ignore[no-untyped-def]
    """A hive-partitioned table folder, as DuckDB, Polars or Spark would read it."""
    return ds.dataset(folder, format="parquet", partitioning="hive").to_table()


def data(i: int) -> bytes:
    values = {"timestamp": i * 0.002, "actual_q": tuple(i + j / 10 for j in range(6)), "robot_mode": 7}
    return CODEC.encode_package(values, recipe_id=1)


def session(conv: Conversation, *, setup: bool = True) -> None:
    conv.handshake()
    if setup:
        conv.send("client", build("request_protocol_version", protocol_version=2))
        conv.send("server", build("request_protocol_version_reply", accepted=True))
        conv.send("client", build("get_urcontrol_version"))
        conv.send("server", build("get_urcontrol_version_reply", major=5, minor=15, bugfix=0, build=1))
        conv.send("client", build("setup_outputs_v2", output_frequency=500.0, variable_names=NAMES))
        conv.send(
            "server",
            build(
                "setup_outputs_v2_reply", output_recipe_id=1, variable_types=["DOUBLE", "VECTOR6D", "INT32"]
            ),
        )
        conv.send("client", build("setup_inputs", variable_names=INPUTS))
        conv.send(
            "server", build("setup_inputs_reply", input_recipe_id=1, variable_types=["INT32", "DOUBLE"])
        )
        conv.send("client", build("start"))
        conv.send("server", build("start_reply", accepted=True))


def edge_cases(tmp_path: Path, fmt: str = "pcap", link: str = "ethernet", ipv6: bool = False) -> Path:
    """One RTDE session with every edge case the issue lists; the expected rows are documented inline."""
    host = ("fd00::2", "fd00::10") if ipv6 else ("10.0.0.2", "10.0.0.10")
    conv = Conversation((host[0], 51000), (host[1], 30004), link=link)
    session(conv)
    for i in range(0, 100):  # 100 packages, one per segment
        conv.send("server", data(i))
    conv.send("server", b"".join(data(i) for i in range(100, 150)))  # 50 packages in one segment
    whole = data(150)
    conv.send("server", whole[:1])  # a package split in the middle of its header ...
    conv.send("server", whole[1:] + data(151)[:40])  # ... and the next split mid-payload
    _, again = conv.send("server", data(151)[40:])
    conv.resend(again)  # a retransmission of that segment
    conv.send("server", data(152), keep=False)  # a lost segment: a gap of one package
    for i in range(153, 200):
        conv.send("server", data(i))
    conv.send(
        "server", build("text_message", message="protective stop", source="SafetySystem", warning_level=1)
    )
    inputs = RecipeCodec.for_names(INPUTS, "input")
    conv.send("client", inputs.encode_package({"input_int_register_24": 42, "speed_slider_fraction": 0.5}, 1))
    conv.send("server", data(200)[:-5])  # the capture ends inside the last package
    return write(tmp_path / f"edge.{fmt}", [conv], fmt)


def test_every_edge_case_is_decoded_or_reported(tmp_path: Path) -> None:
    summary = decode_to_directory(edge_cases(tmp_path), tmp_path / "out")
    (conn,) = summary.connections
    assert conn.kind == "rtde" and conn.name == "10.0.0.2:51000-10.0.0.10:30004"
    assert conn.gaps == 1 and conn.lost_bytes == len(data(152))
    assert any("ends inside a controller package" in e for e in conn.errors)
    assert conn.skipped_bytes == 0 and conn.cut_packages == 0  # the gap: one whole package
    assert len(summary.damage()) == 2 and not summary.needs_recipe()
    table = dataset(tmp_path / "out" / "rtde_outputs_1")
    stamps = [round(t / 0.002) for t in table.column("timestamp").to_pylist()]
    assert stamps == [i for i in range(200) if i != 152]  # in order, nothing twice, only the lost one missing
    assert table.column("actual_q_3").to_pylist()[10] == pytest.approx(10.3)
    assert set(table.column("robot").to_pylist()) == {"10.0.0.10"}
    assert set(table.column("connection").to_pylist()) == {conn.name}
    text = (
        ds.dataset(tmp_path / "out" / "rtde_text", format="parquet", partitioning="hive")
        .to_table()
        .to_pylist()
    )
    assert text[0]["message"] == "protective stop" and text[0]["sender"] == "controller"
    setup = (
        ds.dataset(tmp_path / "out" / "rtde_setup", format="parquet", partitioning="hive")
        .to_table()
        .to_pylist()
    )
    assert [r["package"] for r in setup][:4] == [
        "request_protocol_version",
        "request_protocol_version_reply",
        "get_urcontrol_version",
        "get_urcontrol_version_reply",
    ]
    inputs = dataset(tmp_path / "out" / "rtde_inputs_1")
    assert inputs.column("input_int_register_24").to_pylist() == [42]
    recipes = json.loads(next((tmp_path / "out").glob("recipes-*.json")).read_text())
    assert {r["table"]: r["names"] for r in recipes}["rtde_outputs_1"] == NAMES


def test_capture_time_is_that_of_the_segment_that_completed_each_package(tmp_path: Path) -> None:
    tables = capture_tables(edge_cases(tmp_path))
    rows = tables["rtde_outputs_1"].to_pylist()
    by_index = {round(r["timestamp"] / 0.002): r["capture_time"] for r in rows}
    assert by_index[100] == by_index[149]  # 50 packages in one segment share its time
    assert by_index[150] == by_index[150] and by_index[151] > by_index[150]  # completed by later segments
    assert all(b >= a for a, b in zip(list(by_index.values()), list(by_index.values())[1:], strict=False))


@pytest.mark.parametrize(
    ("fmt", "link", "ipv6"),
    [("pcapng", "ethernet", False), ("pcap", "sll", True), ("pcapng", "loopback", False)],
)
def test_link_types_ip_versions_and_pcapng(tmp_path: Path, fmt: str, link: str, ipv6: bool) -> None:
    tables = capture_tables(edge_cases(tmp_path, fmt, link, ipv6))
    assert tables["rtde_outputs_1"].num_rows == 199


def test_a_capture_that_starts_after_setup(tmp_path: Path) -> None:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    session(conv, setup=False)
    for i in range(30):
        conv.send("server", data(i))
    path = write(tmp_path / "late.pcap", [conv])
    without = decode_to_directory(path, tmp_path / "a")
    (problem,) = without.problems()
    assert (
        "10.0.0.2:51000-10.0.0.10:30004" in problem and "30 of 64 bytes" in problem and "--recipe" in problem
    )
    with_recipe = decode_to_directory(path, tmp_path / "b", recipe_names=NAMES)
    assert not with_recipe.problems() and with_recipe.tables["rtde_outputs_1"] == 30


def test_primary_messages_become_one_table_per_sub_package(tmp_path: Path) -> None:
    import sys

    from .helpers import ROOT

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from ur5e_robot_state import ur5e_robot_state_bytes

    conv = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 30002))
    conv.handshake()
    state = ur5e_robot_state_bytes()
    for _ in range(5):
        conv.send("server", state[:700], dt=0.05)
        conv.send("server", state[700:], dt=0.0)
    conv.send("client", b"set_digital_out(1, True)\n")
    tables = capture_tables(write(tmp_path / "primary.pcap", [conv]))
    joints = tables["primary_joint_data"]
    assert joints.num_rows == 5 and "joints_5_joint_mode" in joints.column_names
    assert joints.column("joints_5_joint_mode").to_pylist() == [253] * 5
    assert tables["primary_cumulative_runtime_data"].num_rows == 5
    assert tables["primary_scripts"].column("script").to_pylist() == ["set_digital_out(1, True)\n"]


def test_what_a_client_sends_in_one_burst_is_one_script_row_however_tcp_cut_it(tmp_path: Path) -> None:
    """A script sent in two TCP segments was two rows, a character cut in two at their edge (its
    bytes in script_raw). A row is a burst: a new def, or a pause after a whole line, starts one."""
    conv = Conversation(("10.0.0.2", 52000), ("10.0.0.10", 30002))
    conv.handshake()
    program = 'def prog():\n  textmsg("héllo")\nend\n'.encode()
    cut = program.index("é".encode()) + 1  # inside the character
    conv.send("client", program[:cut], dt=0.0)
    conv.send("client", program[cut:], dt=0.0002)
    conv.send("client", b"def other():\n  sync()\nend\n", dt=0.001)  # a new program at once
    conv.send("client", b"set_digital_out(1, True)\n", dt=1.0)  # a line after a pause
    conv.send("client", b"set_digital_out(2, ", dt=1.0)  # a line cut by a pause is one row still
    conv.send("client", b"True)\n", dt=1.0)
    tables = capture_tables(write(tmp_path / "scripts.pcap", [conv]))
    scripts = tables["primary_scripts"]
    assert scripts.column("script").to_pylist() == [
        program.decode(),
        "def other():\n  sync()\nend\n",
        "set_digital_out(1, True)\n",
        "set_digital_out(2, True)\n",
    ]
    assert scripts.column("script_raw").to_pylist() == [""] * 4


def test_cli_decodes_a_folder_in_parallel_into_a_hive_dataset(tmp_path: Path) -> None:
    folder = tmp_path / "captures"
    folder.mkdir()
    for name in ("a", "b", "c"):
        conv = Conversation(("10.0.0.2", 51000), (f"10.0.0.{ord(name)}", 30004))
        session(conv)
        for i in range(20):
            conv.send("server", data(i))
        write(folder / f"{name}.pcap", [conv])
    result = cli("capture", str(folder), "-o", str(tmp_path / "out"), "--jobs", "2")
    assert result.returncode == 0, result.stderr
    assert "rtde_outputs_1 (60 rows)" in result.stdout
    table = dataset(tmp_path / "out" / "rtde_outputs_1")
    assert table.num_rows == 60 and len(set(table.column("robot").to_pylist())) == 3
    assert cli("capture", str(tmp_path / "nothing.pcap"), "-o", str(tmp_path / "x")).returncode == 2


def test_a_capture_that_starts_inside_a_package_resyncs(tmp_path: Path) -> None:
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))  # no handshake in the capture
    stream = b"".join(data(i) for i in range(40))
    conv.send("server", stream[25:700])  # the capture begins 25 bytes into the first package
    conv.send("server", stream[700:])
    tables = capture_tables(write(tmp_path / "mid.pcap", [conv]), recipe=NAMES)
    stamps = [round(t / 0.002) for t in tables["rtde_outputs_1"].column("timestamp").to_pylist()]
    assert stamps == list(range(1, 40))


def test_plot_of_a_capture_table(tmp_path: Path) -> None:
    decode_to_directory(edge_cases(tmp_path), tmp_path / "out")
    png = tmp_path / "q.png"
    result = cli("plot", str(tmp_path / "out" / "rtde_outputs_1"), "actual_q", "robot_mode", "-o", str(png))
    assert result.returncode == 0, result.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    missing = cli("plot", str(tmp_path / "out" / "rtde_outputs_1"), "no_such_field", "-o", str(png))
    assert missing.returncode == 2 and "no_such_field" in missing.stderr


@pytest.mark.slow  # a local Dask cluster of two worker processes
def test_dask_on_a_local_cluster_of_two_workers(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed", reason="dask is installed by the test extra")
    from rtde_spec.capture.fleet import capture_bag, dataset_frame

    paths = []
    for k in range(4):
        conv = Conversation(("10.0.0.2", 51000 + k), (f"10.0.2.{k + 1}", 30004))
        session(conv)
        for i in range(25):
            conv.send("server", data(i))
        paths.append(write(tmp_path / f"robot{k}.pcap", [conv]))
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            summaries = capture_bag(paths, tmp_path / "out").compute()
            assert len(client.scheduler_info()["workers"]) == 2
    assert sorted(s.tables["rtde_outputs_1"] for s in summaries) == [25] * 4
    frame = dataset_frame(tmp_path / "out", "rtde_outputs_1").compute()
    assert len(frame) == 100 and frame["robot"].nunique() == 4
    assert frame["actual_q_3"].max() == pytest.approx(24.3)


@pytest.mark.parametrize("fmt", ["pcap", "pcapng"])  # runs: in bulk in pcap blocks, per segment in pcapng
def test_runs_of_data_segments_decode_exactly_as_segment_by_segment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fmt: str
) -> None:
    """Runs (in-order segments of one whole data package each) skip reassembly; nothing else changes."""
    robots = []
    for n, host in enumerate(("10.0.0.10", "10.0.0.11")):
        conv = Conversation((f"10.0.0.{2 + n}", 51000 + n), (host, 30004))
        session(conv)
        robots.append(conv)
    for i in range(300):  # two robots interleaved in blocks of 40: a run goes on over the other's
        conv = robots[(i // 40) % 2]
        conv.time = max(c.time for c in robots)  # one clock, so the file keeps this order
        conv.send("server", data(i))
    robots[0].send("server", b"".join(data(i) for i in range(300, 310)))  # several in one segment
    _, again = robots[0].send("server", data(310))
    robots[0].resend(again)  # a retransmission inside a run
    robots[0].send("server", data(311), keep=False)  # a lost segment
    for i in range(312, 400):
        robots[0].send("server", data(i))
    path = write(tmp_path / f"two.{fmt}", robots, fmt)
    from rtde_spec.capture.protocols.rtde import RtdeConnection
    from tests.capture_files import frame_by_frame, same_rows_per_connection

    runs: list[int] = []
    feed_run = RtdeConnection.feed_run
    monkeypatch.setattr(
        RtdeConnection, "feed_run", lambda self, s, c, d, t: (runs.append(len(t)), feed_run(self, s, c, d, t))
    )
    with_runs = capture_tables(path)
    assert len(runs) >= 2 and sum(runs) >= 250  # the run path did most of the work

    with monkeypatch.context() as patch:
        frame_by_frame(patch)  # every segment routed and fed alone
        one_by_one = capture_tables(path)
    same_rows_per_connection(with_runs, one_by_one)
    rows = with_runs["rtde_outputs_1"]
    assert rows.num_rows == 399  # 400 packages, one lost
    by_connection = {}
    for row in rows.to_pylist():
        by_connection.setdefault(row["connection"], []).append(round(row["timestamp"] / 0.002))
    first, second = sorted(by_connection.values(), key=len, reverse=True)
    assert second == [i for i in range(300) if (i // 40) % 2 == 1]
    assert first == [i for i in range(400) if i != 311 and (i >= 300 or (i // 40) % 2 == 0)]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes are POSIX")
def test_an_interrupted_live_capture_keeps_what_was_decoded(tmp_path: Path) -> None:
    """Ctrl-C while reading a pipe (tcpdump -w - | rtde-spec capture -): the rows decoded so
    far are in whole, readable tables."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    session(conv)
    for i in range(0, 400, 2):
        conv.send("server", data(i) + data(i + 1))  # two per segment: decoded in batches, held a while
    capture = write(tmp_path / "all.pcap", [conv]).read_bytes()
    pipe = tmp_path / "live"
    os.mkfifo(pipe)
    stop = threading.Event()

    def feed() -> None:
        with open(pipe, "wb") as f:
            f.write(capture[: len(capture) // 2])
            f.flush()
            stop.wait(10)  # the rest never comes: the reader is interrupted first

    def interrupt(done: int) -> None:
        if done >= len(capture) // 4:
            raise KeyboardInterrupt

    writer = threading.Thread(target=feed)
    writer.start()
    try:
        with pytest.raises(CaptureInterrupted) as info:  # a KeyboardInterrupt, with what was kept
            decode_to_directory(pipe, tmp_path / "out", progress=interrupt)
    finally:
        stop.set()
        writer.join()
    stamps = dataset(tmp_path / "out" / "rtde_outputs_1").column("timestamp").to_pylist()
    assert 0 < len(stamps) < 400 and stamps == [i * 0.002 for i in range(len(stamps))]
    summary = info.value.summary
    assert summary.tables["rtde_outputs_1"] == len(stamps) and summary.connections[0].packages >= len(stamps)


@pytest.mark.skipif(sys.platform != "linux", reason="reads how much a pipe holds (Linux FIONREAD)")
@pytest.mark.parametrize("ignored", [False, True], ids=["ctrl-c", "kill-int-of-a-background-job"])
def test_ctrl_c_on_a_piped_capture_reports_what_was_kept(tmp_path: Path, ignored: bool) -> None:
    """`ignored`: started as a script's background job (`rtde-spec capture - ... &`), which the
    shell has ignore SIGINT: `kill -INT` was ignored and the capture read on to the input's end."""
    import fcntl
    import signal
    import struct
    import subprocess
    import termios
    import time

    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    session(conv)
    for i in range(300):
        conv.send("server", data(i))
    capture = write(tmp_path / "all.pcap", [conv]).read_bytes()
    cmd = [sys.executable, "-m", "rtde_spec", "capture", "-", "-o", str(tmp_path / "out")]
    started = (lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)) if ignored else None
    proc = subprocess.Popen(
        cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=started
    )
    assert proc.stdin is not None
    proc.stdin.write(capture[: len(capture) // 2])
    proc.stdin.flush()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:  # until the capture has read everything sent
        held = struct.unpack("i", fcntl.ioctl(proc.stdin.fileno(), termios.FIONREAD, b"\0" * 4))[0]
        if not held:
            break
        time.sleep(0.05)
    time.sleep(1.0)  # and decoded it
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err.decode()
    rows = dataset(tmp_path / "out" / "rtde_outputs_1").num_rows
    assert 0 < rows < 300 and f"rtde_outputs_1 ({rows} rows)".encode() in out
    assert b"1 connection\n" in out and b"written whole" in err
