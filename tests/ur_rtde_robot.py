"""The emulator ur_rtde's tests drive: `rtde-spec serve` of this tree on a loopback address of its
own (ur_rtde's ports are fixed), in its own process (ur_rtde holds the GIL while it waits for a
reply), its log collected by a thread as it comes (an unread pipe would fill and hold the
emulator's logging); and the control and receive interfaces connected to it."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import rtde_spec


@dataclass
class Robot:
    control: Any
    receive: Any
    proc: subprocess.Popen[str]
    log: list[str] = field(default_factory=list)
    controller: str = "5.15.0"  # the version the emulator plays


def serve(host: str, controller: str = "5.15.0") -> tuple[subprocess.Popen[str], list[str]]:
    """The emulator of the rtde_spec these tests import (a worktree's, not an installed one's)."""
    tree = str(Path(rtde_spec.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (tree, os.environ.get("PYTHONPATH")) if p)}
    args = ["--host", host, "--dashboard-port", "29999", "--controller", controller, "--model", "UR5e"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "rtde_spec", "serve", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert proc.stdout is not None and proc.stderr is not None
    line = proc.stdout.readline()
    log: list[str] = []
    threading.Thread(target=lambda: log.extend(proc.stderr or ()), daemon=True).start()
    assert re.search(r"realtime 30003", line), line
    return proc, log


@contextmanager
def ur_rtde_robot(
    host: str, rtde_control: Any, rtde_receive: Any, controller: str = "5.15.0"
) -> Iterator[Robot]:
    """ur_rtde's control and receive interfaces on a fresh emulator; all stopped at the end."""
    proc, log = serve(host, controller)
    try:
        control = rtde_control.RTDEControlInterface(host)
        receive = rtde_receive.RTDEReceiveInterface(host)
        try:
            yield Robot(control, receive, proc, log, controller)
        finally:
            control.stopScript()
            control.disconnect()
            receive.disconnect()
    finally:
        proc.terminate()
        proc.wait(10)


def settle_until(
    done: Callable[[], Any], seconds: float = 5.0, what: str = "the outputs never showed it"
) -> None:
    deadline = time.monotonic() + seconds
    while not done():
        assert time.monotonic() < deadline, what
        time.sleep(0.01)


def control_mode(host: str) -> int:
    """The control mode of the next Robot State on the primary port (URCL's primary client reads it)."""
    from rtde_spec import PrimaryClient

    with PrimaryClient(host, 30001, timeout=5) as client:
        for message in client:
            if message.NAME == "robot_state":
                mode = next(p for p in message.sub_packages if type(p).__name__ == "RobotModeData")
                return int(mode.control_mode)
    raise AssertionError("the primary port closed before a Robot State")
