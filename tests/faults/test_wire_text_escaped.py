"""Text from the wire never drives a terminal or a log (issue 31.5).

A controller's RTDE text message reaches `record`'s stderr, a client's reaches `serve`'s
log, a package's text reaches `decode`'s table and capture's summary: each shows escape
sequences as `\\x1b`, never as the raw byte.
"""

from __future__ import annotations

import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

from rtde_spec import build
from rtde_spec.capture.tables.summary import CaptureSummary, ConnectionSummary
from rtde_spec.rtde.client import RtdeClient
from tests.helpers import ROOT

RUN = [sys.executable, "-m", "rtde_spec"]
RECORD = ["--fields", "timestamp", "--samples", "50", "--timeout", "5"]
EVIL = "\x1b]0;pwned\x07\x1b[2J\x1b[31mred"


def _read_package(conn: socket.socket) -> tuple[int, bytes]:
    head = b""
    while len(head) < 3:
        chunk = conn.recv(3 - len(head))
        if not chunk:
            raise ConnectionError("closed")
        head += chunk
    size, kind = struct.unpack(">HB", head)
    body = b""
    while len(body) < size - 3:
        body += conn.recv(size - 3 - len(body))
    return kind, body


def scripted_controller(listener: socket.socket) -> None:
    """A controller's side from the spec: handshake, a recipe, a text message with escapes, close."""
    conn, _ = listener.accept()
    with conn:
        replies = {
            ord("V"): build("request_protocol_version_reply", accepted=True),
            ord("v"): build("get_urcontrol_version_reply", major=5, minor=15, bugfix=0, build=0),
            ord("O"): build("setup_outputs_v2_reply", output_recipe_id=1, variable_types=["DOUBLE"]),
            ord("S"): build("start_reply", accepted=True),
        }
        while True:
            kind, _ = _read_package(conn)
            conn.sendall(replies[kind])
            if kind == ord("S"):
                break
        conn.sendall(build("text_message", message=EVIL, source="\x1b[1mUR", warning_level=1))
        for i in range(5):
            conn.sendall(build("data_package", recipe_id=1, payload=struct.pack(">d", i * 0.002)))
        time.sleep(0.5)


def test_record_prints_the_controllers_text_escaped(tmp_path: Path) -> None:
    listener = socket.create_server(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    peer = threading.Thread(target=scripted_controller, args=(listener,), daemon=True)
    peer.start()
    result = subprocess.run(
        [*RUN, "record", "--host", "127.0.0.1", "--port", str(port), *RECORD, "-o", str(tmp_path / "r.csv")],
        capture_output=True,
        timeout=60,
        cwd=ROOT,
    )
    listener.close()
    stderr = result.stderr.decode()
    assert "\\x1b]0;pwned" in stderr, stderr  # the message was shown ...
    assert "\x1b" not in stderr and "\x07" not in stderr  # ... and not obeyed


def test_serve_logs_a_clients_text_escaped(tmp_path: Path) -> None:
    server = subprocess.Popen(
        [
            *RUN,
            "serve",
            *(f"--{name}-port=0" for name in ("rtde", "primary", "secondary", "realtime", "dashboard")),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=ROOT,
    )
    try:
        assert server.stderr is not None
        port = None
        deadline = time.monotonic() + 30
        seen = b""
        while port is None and time.monotonic() < deadline:
            line = server.stderr.readline()
            seen += line
            if b" rtde on 127.0.0.1:" in line:
                port = int(line.rsplit(b":", 1)[1])
        assert port is not None, seen
        with RtdeClient("127.0.0.1", port) as client:
            client.send_text(EVIL)
            time.sleep(0.5)
    finally:
        server.terminate()
        _, rest = server.communicate(timeout=30)
    log = (seen + rest).decode("utf-8", "replace")
    assert "\\x1b]0;pwned" in log, log[-2000:]
    assert "\x1b" not in log and "\x07" not in log


def test_decode_table_shows_a_text_package_escaped() -> None:
    package = build("text_message", message=EVIL, source="x", warning_level=1).hex()
    result = subprocess.run(
        [sys.executable, "-m", "rtde_spec", "decode", package, "--from", "client"],
        capture_output=True,
        timeout=60,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    assert b"\\x1b]0;pwned" in result.stdout and b"\x1b" not in result.stdout


def test_capture_summary_escapes_what_it_quotes(capsys: object) -> None:
    from rtde_spec.cli.capture_cmd import _report

    summary = CaptureSummary(file="x\x1b[2J.pcap")
    connection = ConnectionSummary(
        name="10.0.0.2:1-10.0.0.10:30004", kind="rtde", packages=1, gaps=0, lost_bytes=0,
        errors=[f"a package quoting {EVIL}"], unknown_recipe_sizes={},
    )  # fmt: skip
    connection.notes.append(f"program name {EVIL}")
    summary.connections.append(connection)
    _report([summary])
    out = capsys.readouterr()  # type: ignore[attr-defined]
    both = out.out + out.err
    assert "\\x1b]0;pwned" in both and "\x1b" not in both
