"""The program of the External Control URCap node (the ROS driver's mode that is not headless).

PolyScope asks the driver for its program when a program holding the node is played: it
connects to the driver's script sender (port 50002 by default), sends `request_program`, and
reads what comes while it keeps coming. The part between `# HEADER_BEGIN` and `# HEADER_END`
(the driver's definitions) goes to the program's header, the rest where the node stands. The
emulator does the same off the control loop (`ControllerModel.run_script_later`): a driver
that is not listening, or sends nothing, is a runtime exception naming where it asked.
"""

from __future__ import annotations

import socket
import time

EXTERNAL_CONTROL = "com.fzi.externalcontrol.ExternalControlNode"  # the node's strategyClass
NODE_MARK = "# rtde-spec: the External Control program"
HEADER_MARK = "# rtde-spec: the External Control header"
MAX_PROGRAM_BYTES = 1 << 20
QUIET_SECONDS = 0.5  # nothing more for this long after the program began: it is all there
CONNECT_SECONDS = 5.0


class ExternalProgramError(OSError):
    """The driver's program could not be had: where it was asked and why."""


def _script_sender() -> tuple[int, bytes]:
    """The script sender's port and the request the URCap sends it (spec/external_control)."""
    from rtde_spec.metamodel.external import external_spec

    sender = external_spec().protocol("script_sender")
    return int(sender.port), (sender.request or "").encode()


def address(text: str | None, default_host: str) -> tuple[str, int]:
    """HOST[:PORT] of the driver's script sender (`serve --external-control`), else the default
    host (the dashboard client that plays the program) on the spec's port (50002)."""
    port = _script_sender()[0]
    if not text:
        return default_host, port
    host, _, given = text.rpartition(":") if text.count(":") == 1 else (text, "", "")
    return (host or text), int(given) if given else port


def fetch(host: str, port: int) -> str:
    """The program the driver sends for `request_program` (UTF-8 text)."""
    where = f"{host}:{port}"
    try:
        with socket.create_connection((host, port), timeout=CONNECT_SECONDS) as sock:
            sock.sendall(_script_sender()[1])
            data = bytearray()
            sock.settimeout(CONNECT_SECONDS)
            deadline = time.monotonic() + 30.0
            while len(data) <= MAX_PROGRAM_BYTES and time.monotonic() < deadline:
                try:
                    chunk = sock.recv(65536)
                except TimeoutError:
                    break
                if not chunk:
                    break
                data += chunk
                sock.settimeout(QUIET_SECONDS)
    except OSError as exc:
        raise ExternalProgramError(f"External Control: no program from {where} ({exc})") from None
    if not data.strip():
        raise ExternalProgramError(f"External Control: {where} sent no program")
    if len(data) > MAX_PROGRAM_BYTES:
        raise ExternalProgramError(f"External Control: {where} sent over {MAX_PROGRAM_BYTES} bytes")
    return data.decode("utf-8", "replace")


def insert(script: str, program: str) -> str:
    """`script` (a translated .urp) with the driver's program at the node and its header on top."""
    lines = program.splitlines()
    marks = [line.strip() for line in lines]
    try:
        begin, end = marks.index("# HEADER_BEGIN"), marks.index("# HEADER_END")
    except ValueError:
        header, body = [], lines
    else:
        header, body = lines[begin + 1 : end], lines[:begin] + lines[end + 1 :]
    return script.replace(HEADER_MARK, "\n".join(header)).replace(NODE_MARK, "\n".join(body))
