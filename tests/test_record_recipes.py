"""`record` with UR's own recipe files, --recipe-key, --wall-clock, and the wrong port (issue 21.2, 21.3).

Against the emulator over loopback, through the CLI's main() as a user runs it.
"""

from __future__ import annotations

import contextlib
import csv
import itertools
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rtde_spec import EmulatorConfig, EmulatorThread
from rtde_spec.cli.main import main
from rtde_spec.cli.port_probe import probe

from .helpers import DATA

UR_CONFIG = DATA / "ur_client_config.xml"  # UR's example: recipes state, setp, watchdog


@pytest.fixture(scope="module")
def emu() -> Iterator[EmulatorThread]:
    config = EmulatorConfig(
        rtde_port=0, primary_port=0, secondary_port=0, dashboard_port=0, realtime_port=None
    )
    config.skip_after = None  # a stall of the loaded machine delays packages, never skips them
    running = EmulatorThread(config).start()
    yield running
    running.stop()


def record(capsys: pytest.CaptureFixture[str], emu: EmulatorThread, *args: str) -> tuple[int, str]:
    code = main(["record", "--host", "127.0.0.1", "--port", str(emu.ports["rtde"]), *args])
    return code, capsys.readouterr().err


def header(path: Path) -> list[str]:
    with open(path, newline="") as f:
        return next(csv.reader(f))


def test_ur_configuration_with_several_recipes_records_its_output_recipe(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "state.csv"
    code, err = record(capsys, emu, "--config", str(UR_CONFIG), "--samples", "5", "-o", str(out))
    assert code == 0, err
    assert header(out) == [
        "timestamp",
        *(f"actual_q_{i}" for i in range(6)),
        "robot_mode",
        "output_int_register_0",
    ]


def test_recipe_key_picks_one_and_an_unknown_key_lists_the_keys(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "watchdog.csv"
    code, err = record(
        capsys, emu, "--recipe", str(UR_CONFIG), "--recipe-key", "watchdog", "--samples", "3", "-o", str(out)
    )
    assert code == 0, err
    assert header(out) == ["input_int_register_24"]
    code, err = record(capsys, emu, "--recipe", str(UR_CONFIG), "--recipe-key", "out", "-o", str(out))
    assert code == 2 and "no recipe keyed 'out'" in err
    assert "state (output, 4 fields), setp (input, 2 fields), watchdog (input, 1 field)" in err


def test_several_output_recipes_without_a_key_is_a_usage_error_naming_them(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    two = tmp_path / "two.xml"
    two.write_text(
        '<rtde_config><recipe key="fast"><field name="timestamp"/></recipe>'
        '<recipe key="slow"><field name="actual_q"/></recipe></rtde_config>'
    )
    out = tmp_path / "o.csv"
    code, err = record(capsys, emu, "--recipe", str(two), "-o", str(out))
    assert code == 2 and "2 output recipes" in err and "fast (output, 1 field)" in err
    assert "pick one with --recipe-key KEY" in err and not out.exists()


def test_a_missing_recipe_file_is_reported_as_a_missing_file(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    code, err = record(capsys, emu, "--recipe", str(tmp_path / "nothere.xml"), "-o", str(tmp_path / "o.csv"))
    assert code == 2 and "no such recipe file" in err and "--fields" in err


def test_wall_clock_adds_host_time_beside_the_timestamp(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "w.csv"
    before = time.time()
    code, err = record(
        capsys, emu, "--fields", "timestamp,actual_q", "--duration", "1", "--wall-clock", "-o", str(out)
    )
    after = time.time()
    assert code == 0, err
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0])[:2] == ["timestamp", "host_time"] and len(rows) > 20
    host = [float(r["host_time"]) for r in rows]
    stamp = [float(r["timestamp"]) for r in rows]
    assert all(before <= h <= after for h in host)
    assert all(b >= a for a, b in itertools.pairwise(host))  # never backwards
    # spaced as the controller stamped the rows: drift only between batches, a fraction of a second
    assert max(abs((h - host[0]) - (t - stamp[0])) for h, t in zip(host, stamp, strict=True)) < 0.25


def test_wall_clock_without_a_timestamp_field_puts_host_time_first(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "w.csv"
    code, err = record(
        capsys, emu, "--fields", "robot_mode", "--samples", "5", "--wall-clock", "-o", str(out)
    )
    assert code == 0, err
    assert header(out) == ["host_time", "robot_mode"]


@pytest.mark.parametrize(
    ("port", "says"),
    [
        ("primary", "speaks the primary/secondary interface (it sent a Version message unprompted"),
        ("secondary", "controller 5.15.0), not RTDE: RTDE is on port 30004"),
        ("dashboard", "speaks the dashboard server (it greeted with 'Connected: Universal Robots"),
    ],
)
def test_record_at_another_interface_says_what_listens_there(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path, port: str, says: str
) -> None:
    out = tmp_path / "o.csv"
    code = main(
        ["record", "--host", "127.0.0.1", "--port", str(emu.ports[port]), "--fields", "timestamp",
         "--timeout", "2", "-o", str(out)]
    )  # fmt: skip
    err = capsys.readouterr().err
    assert code == 1 and says in err, err
    assert "--port 30004" in err and not out.exists()


def test_record_where_nothing_listens_says_so() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        free = s.getsockname()[1]  # closed again: nothing listens there
    result = probe("127.0.0.1", free, 2.0)
    assert result.kind == "closed" and "Connection refused" in result.detail


def _serve(handler: object) -> tuple[socket.socket, threading.Thread]:
    server = socket.create_server(("127.0.0.1", 0))

    def run() -> None:
        conn, _ = server.accept()
        with conn, contextlib.suppress(OSError):  # the probe may hang up once it knows
            handler(conn)  # type: ignore[operator]

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return server, thread


def test_probe_tells_real_time_like_streams_and_silent_ports() -> None:
    probed = threading.Event()  # each peer holds its connection open until the probe has its answer

    def realtime(conn: socket.socket) -> None:  # fixed-size packages, each led by its length
        conn.sendall(((1116).to_bytes(4, "big") + bytes(1112)) * 3)
        probed.wait(5)

    def silent(conn: socket.socket) -> None:
        conn.recv(100)  # reads the RTDE request, answers nothing
        probed.wait(5)

    def other(conn: socket.socket) -> None:
        conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
        probed.wait(5)

    found = {}
    for handler in (realtime, silent, other):
        server, thread = _serve(handler)
        probed.clear()
        with server:
            found[handler.__name__] = probe("127.0.0.1", server.getsockname()[1], 1.0)
        probed.set()
        thread.join(5)
    assert found["realtime"].kind == "realtime" and "1116-byte packages" in found["realtime"].detail
    assert found["silent"].kind == "silent" and "did not answer an RTDE request" in found["silent"].detail
    assert found["other"].kind == "unknown" and "53 53 48 2d" in found["other"].detail


def test_a_server_that_closes_at_once_is_not_said_to_speak_another_protocol() -> None:
    """A controller (or the emulator) at its client limit or out of descriptors accepts and
    closes at once: that was "does not speak RTDE: it sends nothing", sending users to check
    a port that was right."""
    from rtde_spec.cli.port_probe import wrong_port

    def closes(conn: socket.socket) -> None:
        conn.close()

    server, thread = _serve(closes)
    with server:
        found = probe("127.0.0.1", server.getsockname()[1], 1.0)
    thread.join(5)
    assert found.kind == "refused" and "closed the connection at once" in found.detail
    server, thread = _serve(closes)
    with server:  # what a refused `record` prints
        said = wrong_port("127.0.0.1", server.getsockname()[1], "rtde", 1.0)
    thread.join(5)
    assert said is not None and "does not speak" not in said
    assert "try again once another client has left" in said


def test_decode_with_ur_configuration_picks_the_recipe_of_the_sender(
    capsys: pytest.CaptureFixture[str],
) -> None:
    import json

    from rtde_spec.recipes.codec import RecipeCodec

    names = ["timestamp", "actual_q", "robot_mode", "output_int_register_0"]
    values = {"timestamp": 1.5, "actual_q": (0.25,) * 6, "robot_mode": 7, "output_int_register_0": 42}
    package = RecipeCodec.for_names(names, "output").encode_package(values, 1)
    assert main(["decode", package.hex(), "--recipe", str(UR_CONFIG), "--format", "json"]) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert (row["timestamp"], row["output_int_register_0"]) == (1.5, 42)
    setp = RecipeCodec.for_names(["input_double_register_24", "input_double_register_25"], "input")
    sent = setp.encode_package({"input_double_register_24": 0.5, "input_double_register_25": -1.0}, 2)
    argv = ["decode", sent.hex(), "--from", "client", "--recipe", str(UR_CONFIG), "--recipe-key", "setp"]
    assert main([*argv, "--format", "json"]) == 0
    (row,) = json.loads(capsys.readouterr().out)
    assert (row["input_double_register_24"], row["input_double_register_25"]) == (0.5, -1.0)


def test_decode_to_dash_writes_standard_output_and_capture_to_dash_is_refused(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """`-o -` wrote a file named `-`; record refused it. Now it is standard output where one
    file goes to it, and refused where the output is a folder."""
    import json

    from rtde_spec.recipes.codec import RecipeCodec

    monkeypatch.chdir(tmp_path)
    package = RecipeCodec.for_names(["timestamp"], "output").encode_package({"timestamp": 2.5}, 1)
    assert main(["decode", package.hex(), "--recipe", "timestamp", "--format", "json", "-o", "-"]) == 0
    assert [row["timestamp"] for row in json.loads(capsys.readouterr().out)] == [2.5]
    assert main(["demo", "-o", "-"]) == 2
    assert "-o -: standard output cannot hold a folder of files" in capsys.readouterr().err
    (tmp_path / "in.bin").write_bytes(b"")
    with pytest.raises(SystemExit) as refused:  # argparse's own exit for a bad option value
        main(["capture", str(tmp_path / "in.bin"), "-o", "-"])
    assert refused.value.code == 2
    assert "standard output cannot hold a folder of tables" in capsys.readouterr().err
    (tmp_path / "in.bin").unlink()
    record_argv = ["record", "--host", "127.0.0.1", "--port", "1", "--fields", "timestamp", "--format", "csv"]
    assert main([*record_argv, "-o", "-"]) == 2
    assert "-o -: this output is a file, written whole at the end" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_fields_given_twice_are_both_recorded(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """The second --fields replaced the first, silently."""
    out = tmp_path / "f.csv"
    code, err = record(
        capsys,
        emu,
        "--fields",
        "timestamp,actual_q",
        "--fields",
        "robot_mode",
        "--samples",
        "3",
        "-o",
        str(out),
    )
    assert code == 0, err
    assert header(out) == ["timestamp", *(f"actual_q_{i}" for i in range(6)), "robot_mode"]


@pytest.mark.parametrize("frequency", ["125", "500"])
def test_a_duration_is_that_many_seconds_of_the_controllers_rows(
    emu: EmulatorThread, capsys: pytest.CaptureFixture[str], tmp_path: Path, frequency: str
) -> None:
    """--duration 1 at 125 Hz is 125 rows, not the ~25 more a clock checked once a batch let in
    (UR's record.py with --samples is the comparison: it stops at the count)."""
    out = tmp_path / "d.csv"
    args = ["--fields", "timestamp", "--frequency", frequency, "--duration", "1", "-o", str(out)]
    code, err = record(capsys, emu, *args)
    assert code == 0, err
    with open(out, newline="") as f:
        stamps = [float(r["timestamp"]) for r in csv.DictReader(f)]
    assert len(stamps) == int(frequency), err
    step = 1 / int(frequency)
    assert all(abs(b - a - step) < 1e-6 for a, b in itertools.pairwise(stamps))  # none lost
    assert f"recorded {frequency} rows" in err and "stopped by duration" in err
