"""Every code block of README.md and docs/*.md runs as written, so none can rot.

Blocks run as a user runs them: in the folder `rtde-spec examples DIR` writes (the
example files the package ships: captures, recipes, a script, a scenario...), with
`python3` and `rtde-spec` on the PATH being this interpreter (a venv's too), beside
the controller emulator on its default ports on 127.0.0.1, which is what the docs
point commands at. The install and test commands of the README are checked against
`.ci/run` instead of being run inside the test run they start.
"""

from __future__ import annotations

import errno
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from .docs_blocks import LANGUAGES, ROOT, Block, blocks, commands, documents
from .fixed_ports import WAIT, wait_until_free

# the emulator on the default ports of 127.0.0.1: every test here in one process (pytest-xdist),
# taking turns for those ports with any other test run on the machine (tests/fixed_ports.py)
HOST = "127.0.0.1"
pytestmark = [pytest.mark.xdist_group("docs"), pytest.mark.fixed_ports(HOST)]

ALL = [b for doc in documents() for b in blocks(doc)]
RUNNABLE = [b for b in ALL if b.language in ("python", "sh")]


class Robot:
    """The emulator on the default ports, as `rtde-spec serve` runs it; stopped for blocks that start one."""

    def __init__(self) -> None:
        self.thread: Any = None

    def start(self) -> None:
        """Start it, waiting while something outside this run holds a port (it takes no turns)."""
        from rtde_spec import EmulatorConfig, EmulatorThread

        deadline = time.monotonic() + WAIT
        while self.thread is None:
            wait_until_free(HOST, wait=max(1.0, deadline - time.monotonic()))
            try:
                self.thread = EmulatorThread(EmulatorConfig(host=HOST)).start()  # serve's ports
            except OSError as exc:
                if exc.errno != errno.EADDRINUSE or time.monotonic() > deadline:
                    raise

    def stop(self) -> None:
        if self.thread is not None:
            self.thread.stop()
            self.thread = None


@pytest.fixture(scope="module")
def robot() -> Iterator[Robot]:
    held = Robot()
    held.start()
    try:
        yield held
    finally:
        held.stop()


@pytest.fixture(scope="session")  # not module: a worker that runs another module between two
def workspace(tmp_path_factory: pytest.TempPathFactory) -> Path:  # blocks keeps what the first made
    folder = tmp_path_factory.mktemp("docs") / "rtde-examples"
    env = _env(folder.parent)
    made = subprocess.run(["rtde-spec", "examples", str(folder)], env=env, capture_output=True, text=True)
    assert made.returncode == 0, made.stderr
    for block in ALL:  # files the docs show first and use later
        if "file" in block.directives:
            (folder / block.directives["file"]).write_text(block.text, encoding="utf-8")
    return folder


def _env(folder: Path) -> dict[str, str]:
    """PATH with `python3` and `rtde-spec` running this interpreter.

    Scripts, not a symlink: Python finds its venv from the path it was started by, so a
    link to a venv's python elsewhere starts the base Python without the venv's packages.
    """
    bin_dir = folder / ".bin"
    bin_dir.mkdir(exist_ok=True)
    for name, tail in (("python3", ""), ("rtde-spec", " -m rtde_spec")):
        script = bin_dir / name
        if not script.exists():
            script.write_text(f'#!/bin/sh\nexec "{sys.executable}"{tail} "$@"\n')
            script.chmod(0o755)
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["MPLBACKEND"] = "Agg"
    return env


def test_every_block_has_a_language_the_suite_knows() -> None:
    unknown = [f"{b.id} ({b.language or 'none'})" for b in ALL if b.language not in LANGUAGES]
    assert not unknown, f"give these blocks a language ({', '.join(sorted(LANGUAGES))}): {unknown}"
    assert len(RUNNABLE) >= 10


@pytest.mark.parametrize(
    "block", [b for b in ALL if b.language in ("yaml", "xml", "json")], ids=lambda b: b.id
)
def test_data_blocks_parse(block: Block) -> None:
    if block.language == "yaml":
        yaml.safe_load(block.text)
    elif block.language == "json":
        json.loads(block.text)
    else:
        import defusedxml.ElementTree as ET

        ET.fromstring(block.text)


def _ci_step(part: str) -> bool:
    """The README's install and test commands: checked against .ci/run, not run here."""
    ci = (ROOT / ".ci" / "run").read_text()
    part = part.split(" #")[0].strip()  # the line's comment
    if part.startswith("python3 -m pip install"):
        assert "python3 -m pip install" in ci and ".[test]" in ci
        return True
    if part == "python3 -m pytest":
        assert "\npython3 -m pytest\n" in ci, ".ci/run must run exactly the README's test command"
        return True
    return False


def _listening(port: int) -> bool:
    try:
        socket.create_connection((HOST, port), timeout=0.5).close()
    except OSError:
        return False
    return True


def _run_until_stopped(
    command: str, folder: Path, env: dict[str, str], seconds: float, ready: int | None = None
) -> None:
    """Run a command that serves until Ctrl-C for `seconds`, or (with `ready`) until that port
    accepts and a second more has passed: long enough to see it serve, not a fixed wait."""
    proc = subprocess.Popen(
        command, shell=True, cwd=folder, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        start_new_session=True,
    )  # fmt: skip
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline and proc.poll() is None:
        if ready is not None and _listening(ready):
            deadline = min(deadline, time.monotonic() + 1.0)
            ready = None
        time.sleep(0.1)
    if proc.poll() is not None:
        _, err = proc.communicate()
        raise AssertionError(f"{command!r} ended early (exit {proc.returncode}): {err.decode()[-800:]}")
    os.killpg(proc.pid, signal.SIGINT)
    try:
        proc.wait(20)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        raise AssertionError(f"{command!r} did not stop on Ctrl-C") from None
    err = proc.stderr.read().decode() if proc.stderr else ""
    assert "Traceback" not in err, err[-800:]


@pytest.mark.parametrize("block", RUNNABLE, ids=lambda b: b.id)
def test_block_runs(block: Block, workspace: Path, robot: Robot) -> None:
    env = _env(workspace)
    if "own-emulator" in block.directives:
        robot.stop()
        wait_until_free(HOST)
        try:
            _run(block, workspace, env)
        finally:
            robot.start()
    else:
        robot.start()
        _run(block, workspace, env)


def _run(block: Block, workspace: Path, env: dict[str, str]) -> None:
    if block.language == "python":
        result = subprocess.run(
            [sys.executable, "-c", block.text], cwd=workspace, env=env, capture_output=True, text=True,
            timeout=180,
        )  # fmt: skip
        assert result.returncode == 0, f"{block.id}:\n{result.stderr[-2000:]}"
        if "prints" in block.directives:  # what the reader is told the block shows
            wanted = block.directives["prints"].replace("+", " ")
            assert wanted in result.stdout, f"{block.id} should print {wanted!r}:\n{result.stdout[-2000:]}"
            assert "\nNone\n" not in f"\n{result.stdout}", f"{block.id} prints None:\n{result.stdout}"
        return
    until = block.directives.get("until-stopped")
    for command in commands(block):
        parts = [p.strip() for p in command.split(" && ")]
        rest = " && ".join(p for p in parts if not _ci_step(p))
        if not rest:
            continue
        if until is not None:
            ready = block.directives.get("ready")
            _run_until_stopped(rest, workspace, env, float(until), int(ready) if ready else None)
            continue
        result = subprocess.run(
            rest, shell=True, cwd=workspace, env=env, capture_output=True, text=True, timeout=180
        )
        expected = int(block.directives.get("exit", "0"))
        assert result.returncode == expected, (
            f"{block.id}: {rest!r} exit {result.returncode}:\n{result.stderr[-2000:]}"
        )
