"""What a newcomer's first hour ran into (issue 28), each held: messages, exit codes, versions."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import pytest

from rtde_spec.cli.demo_online import demo_folder
from rtde_spec.cli.main import main
from rtde_spec.errors import UsageError, install_hint

from .capture_files import Conversation, write
from .docs_workspace import SHIPPED

ROOT = Path(__file__).resolve().parents[1]


def run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    try:
        code = main(list(args))
    except SystemExit as stop:  # argparse's usage errors
        code = int(stop.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


def test_a_capture_without_ur_traffic_is_exit_3_naming_the_ports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    web = Conversation(("10.0.0.2", 50500), ("10.0.0.10", 8080))
    web.handshake()
    web.send("client", b"GET / HTTP/1.1\r\n\r\n")
    web.send("server", b"HTTP/1.1 200 OK\r\n\r\n")
    capture = write(tmp_path / "web.pcap", [web])
    code, out, err = run(capsys, "capture", str(capture), "-o", str(tmp_path / "out"))
    assert code == 3
    assert "0 connections" in out and "tables: none" in out
    assert ": ok:" not in err and "nothing decoded" in err
    assert "TCP ports seen: 8080 (4 segments)" in err and "--port-map" in err


def test_a_capture_needing_a_recipe_is_not_ok(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "capture", str(SHIPPED / "late.pcap"), "-o", str(tmp_path / "late"))
    assert code == 1 and "1 connection\n" in out and "(1 rows)" not in out
    assert ": ok:" not in err and "needs --recipe" in err
    code, out, err = run(
        capsys, "capture", str(SHIPPED / "late.pcap"), "-o", str(tmp_path / "late"),
        "--recipe", str(SHIPPED / "outputs.txt"),
    )  # fmt: skip
    assert code == 0 and "rtde_outputs_1 (100 rows)" in out and "late.pcap: ok:" in err


@pytest.mark.parametrize("name", ["afile", "out.parquet"])
def test_capture_refuses_a_file_for_its_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str
) -> None:
    (tmp_path / "afile").write_text("x")
    target = tmp_path / name
    code, _, err = run(capsys, "capture", str(SHIPPED / "robot.pcapng"), "-o", str(target))
    assert code == 2 and str(target) in err and "capture writes a folder" in err
    assert "Errno" not in err and not (tmp_path / "out.parquet").exists()


def test_a_controller_version_is_major_minor_bugfix(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["validate", "timestamp", "--controller", "5.12"])
    assert stop.value.code == 2
    assert "'5.12' is not a controller version: give MAJOR.MINOR.BUGFIX" in capsys.readouterr().err


def test_a_release_the_spec_does_not_know_is_warned_with_the_nearest(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, _, err = run(capsys, "validate", "timestamp", "--controller", "5.99.0")
    newest = re.search(r"release the spec knows \((5\.\d+\.\d+)\)", err)
    assert code == 0 and newest is not None and f"nearest known: {newest.group(1)}" in err
    for known in ("5.12.2", "3.15.8", "10.11.0"):
        code, _, err = run(capsys, "validate", "timestamp", "--controller", known)
        assert code == 0 and "warning" not in err


def test_a_scenario_and_the_command_line_that_disagree_is_an_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scenario = tmp_path / "s.yaml"
    scenario.write_text("controller: 5.15.0\n")
    code, _, err = run(
        capsys, "serve", "--controller", "3.15.8", "--scenario", str(scenario), "--rtde-port", "0",
        "--primary-port", "0", "--secondary-port", "0", "--dashboard-port", "-1", "--realtime-port", "-1",
    )  # fmt: skip
    assert code == 2 and "--controller 3.15.8 and the scenario's controller: 5.15.0 disagree" in err


def test_install_hints_name_extras_that_exist() -> None:
    extras = set(re.findall(r"^(\w[\w-]*) = \[", (ROOT / "pyproject.toml").read_text(), re.M))
    used = set()
    for path in (ROOT / "rtde_spec").rglob("*.py"):
        used |= set(re.findall(r'require\("[\w.]+", "([\w-]+)"', path.read_text()))
    assert used and used <= extras, used - extras
    assert install_hint("foxglove").startswith('pip install -e ".[foxglove]"')  # run from a checkout


def test_the_demo_writes_to_a_temp_folder_or_the_one_named(tmp_path: Path) -> None:
    made = demo_folder(None)
    assert made.is_dir() and made.parent == Path(tempfile.gettempdir())
    made.rmdir()
    assert demo_folder(tmp_path / "mine") == tmp_path / "mine" and (tmp_path / "mine").is_dir()
    (tmp_path / "afile").write_text("x")
    with pytest.raises(UsageError, match="is a file, but this output is a folder"):
        demo_folder(tmp_path / "afile")


def test_an_emulator_thread_serves_the_ports_serve_does_each_on_a_free_one() -> None:
    import socket

    from rtde_spec import EmulatorConfig, EmulatorThread

    with EmulatorThread(EmulatorConfig.free_ports()) as emu:
        assert set(emu.ports) >= {"rtde", "primary", "secondary", "realtime", "dashboard"}
        assert all(port > 0 for port in emu.ports.values())
        with socket.create_connection(("127.0.0.1", emu.ports["dashboard"]), timeout=5) as dashboard:
            assert dashboard.makefile("r").readline().startswith("Connected: Universal Robots Dashboard")
    with EmulatorThread(EmulatorConfig.free_ports(dashboard_port=None)) as emu:
        assert "dashboard" not in emu.ports and "realtime" in emu.ports


def test_a_host_name_that_does_not_resolve_is_said_so() -> None:
    import socket

    from rtde_spec.cli.port_probe import unreachable

    # the resolver's own error (no lookup is made here: the tests stay on 127.0.0.1)
    found = unreachable("robot.local", socket.gaierror(socket.EAI_NONAME, "Name or service not known"))
    assert found.kind == "unresolved"
    assert (
        "the name 'robot.local' does not resolve to an address" in found.detail
        and "IP address" in found.detail
    )
    refused = unreachable("127.0.0.1", ConnectionRefusedError(111, "Connection refused"))
    assert refused.kind == "closed" and "nothing accepts connections there" in refused.detail


def test_record_checks_the_xml_types_as_validate_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    xml = tmp_path / "config.xml"
    xml.write_text(
        '<?xml version="1.0"?>\n<rtde_config>\n  <recipe key="out">\n'
        '    <field name="timestamp" type="DOUBLE"/>\n    <field name="robot_mode" type="UINT32"/>\n'
        "  </recipe>\n</rtde_config>\n"
    )
    code, _, err = run(capsys, "validate", str(xml))
    assert code == 1 and "the recipe says UINT32, the spec says INT32" in err + _
    target = tmp_path / "r.csv"
    code, _, err = run(
        capsys, "record", "--host", "127.0.0.1", "--port", "9", "--config", str(xml), "-o", str(target)
    )
    assert code == 1 and not target.exists()
    (line,) = [x for x in err.splitlines() if x.startswith("error:")]  # one message, before connecting
    assert f"--recipe {xml} (recipe out): robot_mode: the recipe says UINT32, the spec says INT32" in line


@pytest.mark.parametrize(
    ("output", "says"),
    [
        ("nodir/sub/r.csv", "the folder nodir/sub does not exist; make it first (mkdir -p nodir/sub)"),
        ("afile/r.csv", "afile is a file, not a folder"),
        ("adir/", "is a folder, but this output is one file"),
    ],
)
def test_file_outputs_name_the_path_given_in_plain_words(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    output: str,
    says: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    for argv in (
        ["record", "--host", "127.0.0.1", "--port", "9", "--fields", "timestamp", "-o", output],
        ["decode", "00045601", "-o", output],
    ):
        code, _, err = run(capsys, *argv)
        assert code == 2 and f"error: -o {output}: {says}" in err and "Errno" not in err, argv


def test_a_capture_with_connections_but_no_rows_is_exit_3_naming_the_ports(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rtde = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde.handshake()  # a connection to the RTDE port that never says a word
    capture = write(tmp_path / "quiet.pcap", [rtde])
    code, out, err = run(capsys, "capture", str(capture), "-o", str(tmp_path / "out"))
    assert code == 3 and "1 connection\n" in out and "tables: none" in out
    assert ": ok:" not in err and "no rows found; TCP ports seen: 30004" in err and "--port-map" in err


def test_ctrl_c_ends_the_demo_early_with_what_it_recorded(tmp_path: Path) -> None:
    """Ctrl-C in the middle of the demo's recording: its rows so far are written, summarised and
    plotted, and the demo says it stopped early (a terminal's Ctrl-C: SIGINT as the default)."""
    import signal
    import subprocess
    import sys
    import time

    proc = subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "demo", "-o", str(tmp_path / "out"), "--seconds", "60"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as a shell's foreground job
    )
    assert proc.stdout is not None
    for line in proc.stdout:  # recording runs once the program is announced
        if line.startswith("Sending this URScript"):
            break
    time.sleep(1.5)
    proc.send_signal(signal.SIGINT)
    out = proc.stdout.read()
    assert proc.wait(20) == 0, out
    rows = (tmp_path / "out" / "joints.csv").read_text().splitlines()
    assert len(rows) > 100  # 125 Hz for 1.5 s at least, the header besides
    assert "stopped early by Ctrl-C" in out and "actual_q_0" in out
