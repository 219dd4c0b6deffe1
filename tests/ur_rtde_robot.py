"""The emulator ur_rtde's tests drive: `rtde-spec serve` of this tree on a loopback address of its
own (ur_rtde's ports are fixed), in its own process (ur_rtde holds the GIL while it waits for a
reply), its log collected by a thread as it comes (an unread pipe would fill and hold the
emulator's logging); and the control and receive interfaces connected to it."""

from __future__ import annotations

import json
import os
import queue
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


def serve(
    host: str, controller: str = "5.15.0", model: str = "UR5e", programs: Path | None = None
) -> tuple[subprocess.Popen[str], list[str]]:
    """The emulator of the rtde_spec these tests import (a worktree's, not an installed one's)."""
    tree = str(Path(rtde_spec.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (tree, os.environ.get("PYTHONPATH")) if p)}
    args = ["--host", host, "--dashboard-port", "29999", "--controller", controller, "--model", model]
    args += ["--programs", str(programs)] if programs is not None else []
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
    host: str, rtde_control: Any, rtde_receive: Any, controller: str = "5.15.0", model: str = "UR5e"
) -> Iterator[Robot]:
    """ur_rtde's control and receive interfaces on a fresh emulator; all stopped at the end."""
    proc, log = serve(host, controller, model)
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


class ClientError(Exception):
    """An exception a ur_rtde client raised in the worker: its class name and message."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(f"{kind}: {message}")
        self.kind, self.message = kind, message


class Clients:
    """ur_rtde's clients in a process of their own (tests/ur_rtde_worker.py): every call is answered
    within `deadline` seconds or the test fails saying which call hung (the worker is then killed)."""

    def __init__(self, deadline: float = 10.0) -> None:
        worker = str(Path(__file__).with_name("ur_rtde_worker.py"))
        self.deadline = deadline
        self.proc = subprocess.Popen(
            [sys.executable, worker], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )
        self.replies: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if line.startswith("@ur_rtde_worker "):
                self.replies.put(line.split(" ", 1)[1])

    def _ask(self, request: dict[str, Any], what: str) -> Any:
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        try:
            reply = json.loads(self.replies.get(timeout=self.deadline))
        except queue.Empty:
            self.close()
            raise AssertionError(f"{what} gave no answer within {self.deadline} s") from None
        if "error" in reply:
            raise ClientError(reply["error"], reply["message"])
        return reply["ok"]

    def new(self, name: str, module: str, cls: str, *args: Any) -> None:
        self._ask({"name": name, "new": [module, cls], "args": list(args)}, f"{cls}{args}")

    def call(self, name: str, method: str, *args: Any) -> Any:
        return self._ask({"name": name, "method": method, "args": list(args)}, f"{name}.{method}{args}")

    def close(self) -> None:
        self.proc.kill()
        self.proc.wait(10)
