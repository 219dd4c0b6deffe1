"""Real bytes to try the library on without a robot: the demo's embedded examples.

`primary_stream()` is a primary-interface stream (a Version message, a UR5e-like
Robot State of 13 sub-packages, a text message); `rtde_session()` an RTDE session in
protocol 2 as both sides send it, every package type once, with the data package of
its output recipe. The docs' snippets use them, so every snippet runs as written.
"""

from __future__ import annotations

from importlib import resources
from typing import Literal

Sender = Literal["client", "controller"]


def _text(name: str) -> str:
    return resources.files(__name__).joinpath(name).read_text("utf-8")


def primary_stream() -> bytes:
    """The embedded primary stream's bytes (messages back to back, as a socket gives them)."""
    lines = [line for line in _text("primary_stream.hex").splitlines() if not line.startswith("#")]
    return bytes.fromhex("".join(lines).replace(" ", ""))


def rtde_session() -> list[tuple[Sender, bytes, str]]:
    """(sender, package bytes, note) for every package of the embedded RTDE session."""
    out: list[tuple[Sender, bytes, str]] = []
    for line in _text("rtde_session_v2.txt").splitlines():
        body, _, note = line.partition("#")
        parts = body.split()
        if len(parts) != 2:
            continue
        sender: Sender = "client" if parts[0] == "client" else "controller"
        out.append((sender, bytes.fromhex(parts[1]), note.strip()))
    return out


def ur_rtde_default_outputs() -> list[str]:
    """The output recipe ur_rtde's RTDEReceiveInterface subscribes to by default."""
    return [
        line.strip()
        for line in _text("ur_rtde_default_outputs.txt").splitlines()
        if line.strip() and not line.startswith("#")
    ]
