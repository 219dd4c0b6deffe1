"""The emulator for code that is not asyncio (tests, the demo): in a background thread of this
process (`EmulatorThread`) or in a process of its own (`EmulatorProcess`).

A thread shares the GIL with the process's other threads. Its control loop takes the GIL back a
dozen times a step (each event-loop turn's epoll_wait, the clock's timerfd, the sends); while the
other threads wait in system calls (a client blocked in `recv`, as `RtdeClient` between packages)
that costs nothing, and an input sent right after a package is in the next one as often as from
a process (tests/test_emulator_embedded_inputs.py). A thread that runs Python meanwhile holds each
of those up to the switch interval (`EmulatorConfig.switch_interval`), a call that keeps the GIL
(a full garbage collection of a large heap) holds the loop for all of it, and an extension that
blocks holding it stops the loop: ur_rtde's clients wait for the controller's replies holding the
GIL, so against a thread of their own process they never connect. A loop held up 0.1 s skips
steps (`EmulatorConfig.skip_after`, one log line): inputs then look taken 100 ms late. A process
has its own GIL: `EmulatorProcess` serves the same configuration from a child interpreter, its
state reached through its ports, as a robot's (docs/decisions.md).
"""

from __future__ import annotations

import asyncio
import logging
import os
import pickle
import signal
import subprocess
import sys
import threading
from pathlib import Path

from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.server.loop import Emulator, EmulatorConfig
from rtde_spec.errors import UsageError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.printable import SafeFormatter

log = logging.getLogger("rtde_spec.emulator")
START_TIMEOUT = 60.0  # s for a child to import, build its model and listen (a loaded machine)
CHILD = "from rtde_spec.emulator.server.embedded import serve_child; serve_child()"


class EmulatorThread:
    """An Emulator in a background thread: `with EmulatorThread(config) as emu: ...`.

    Its state is at hand (`model`, `call`); its loop shares the GIL with this process's threads
    (see above): `EmulatorProcess` where they run Python or block holding it (ur_rtde)."""

    def __init__(self, config: EmulatorConfig | None = None, catalogue: Catalogue | None = None) -> None:
        self.emulator = Emulator(config, catalogue)
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._run, name="rtde-emulator", daemon=True)
        self._ready = threading.Event()
        self._error: BaseException | None = None

    @property
    def ports(self) -> dict[str, int]:
        return self.emulator.ports

    @property
    def model(self) -> ControllerModel:
        return self.emulator.model

    def _run(self) -> None:
        asyncio.set_event_loop(self._loop)
        try:
            self._loop.run_until_complete(self.emulator.start())
        except BaseException as exc:
            # the ports opened before the one that failed are closed: a failed start left them
            # listening for the life of the process, so every later start there failed too
            self._loop.run_until_complete(self.emulator.stop())
            _close_loop(self._loop)
            self._error = exc
            self._ready.set()
            return
        self._ready.set()
        try:
            self._loop.run_forever()
        finally:
            _close_loop(self._loop)

    def start(self) -> EmulatorThread:
        """Serve (a running one is returned as it is: `with emu` after `emu.start()`). One that
        stopped does not start again ("threads can only be started once"): make a new one."""
        if self._thread.is_alive():
            return self
        if self._thread.ident is not None:
            raise UsageError("this EmulatorThread has stopped; make a new EmulatorThread(config) to serve")
        self._thread.start()
        self._ready.wait(10)
        if self._error is not None:
            raise self._error
        return self

    def stop(self) -> None:
        if not self._thread.is_alive():
            if self._thread.ident is None and not self._loop.is_closed():  # never started
                self._loop.close()
            return
        future = asyncio.run_coroutine_threadsafe(self.emulator.stop(), self._loop)
        future.result(10)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(10)

    def call(self, fn, *args):  # type: ignore[no-untyped-def]
        """Run fn(*args) in the emulator's loop (its state is not thread-safe) and return the result."""

        async def run():  # type: ignore[no-untyped-def]
            return fn(*args)

        return asyncio.run_coroutine_threadsafe(run(), self._loop).result(10)

    def __enter__(self) -> EmulatorThread:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _close_loop(loop: asyncio.AbstractEventLoop) -> None:
    """End a loop as asyncio.run does: its tasks cancelled, its async generators and its default
    executor (the thread that resolved the listening addresses) shut down, then closed. A loop
    left open held three descriptors (its selector, its wake-up pair) and that thread until the
    garbage collector found it: 30 descriptors and 10 threads after ten emulators."""
    try:
        tasks = asyncio.all_tasks(loop)
        for task in tasks:
            task.cancel()
        if tasks:
            loop.run_until_complete(asyncio.gather(*tasks, return_exceptions=True))
        loop.run_until_complete(loop.shutdown_asyncgens())
        loop.run_until_complete(loop.shutdown_default_executor())
    finally:
        loop.close()


class EmulatorProcess:
    """An Emulator in a process of its own: `with EmulatorProcess(config) as emu: emu.ports`.

    The child is this interpreter with this rtde_spec, serving `config` as `EmulatorThread` would;
    it logs to this process's stderr at the level `rtde_spec.emulator` has here, and ends when
    `stop()` closes its input or this process ends. Its model is out of reach: ask its ports."""

    def __init__(self, config: EmulatorConfig | None = None) -> None:
        self.config = config or EmulatorConfig()
        self.ports: dict[str, int] = {}
        self._proc: subprocess.Popen[bytes] | None = None

    @property
    def pid(self) -> int | None:
        return None if self._proc is None else self._proc.pid

    def start(self) -> EmulatorProcess:
        order = pickle.dumps((self.config, log.getEffectiveLevel()))
        tree = str(Path(__file__).resolve().parents[3])  # this rtde_spec, not another installed one
        path = os.pathsep.join(p for p in (tree, os.environ.get("PYTHONPATH")) if p)
        env = {**os.environ, "PYTHONPATH": path}
        self._proc = proc = subprocess.Popen(
            [sys.executable, "-c", CHILD], stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env
        )
        assert proc.stdin is not None and proc.stdout is not None
        timer = threading.Timer(START_TIMEOUT, proc.kill)  # a child that never answers is ended
        timer.start()
        try:
            proc.stdin.write(order)
            proc.stdin.flush()
            reply = pickle.load(proc.stdout)  # the ports, or what stopped the start
        except (EOFError, BrokenPipeError):
            reply = RuntimeError(f"the emulator's process ended before serving (exit code {proc.wait()})")
        except BaseException:  # interrupted while it started: it does not outlive the start
            self.stop()
            raise
        finally:
            timer.cancel()
        if isinstance(reply, BaseException):
            self.stop()
            raise reply
        self.ports = reply
        return self

    def stop(self) -> None:
        proc, self._proc = self._proc, None
        if proc is None or proc.stdin is None or proc.stdout is None:
            return
        try:
            proc.stdin.close()  # its input ends: it stops serving and exits
        except OSError:
            pass
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        proc.stdout.close()

    def __enter__(self) -> EmulatorProcess:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


def serve_child() -> None:
    """`EmulatorProcess`'s child: the configuration from stdin, the ports (or the exception that
    stopped the start) to stdout, then serving until stdin ends. Ctrl-C in a terminal is the
    parent's to act on: the child ends with its input."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    config, level = pickle.load(sys.stdin.buffer)
    logging.basicConfig(format="%(asctime)s %(message)s")
    for handler in logging.getLogger().handlers:  # what clients send is logged, never obeyed
        handler.setFormatter(SafeFormatter("%(asctime)s %(message)s"))
    log.setLevel(level)
    asyncio.run(_serve(config))


async def _serve(config: EmulatorConfig) -> None:
    emulator: Emulator | None = None
    try:
        emulator = Emulator(config)
        await emulator.start()
    except Exception as exc:
        if emulator is not None:
            await emulator.stop()  # the ports it opened before the one that failed
        _answer(_picklable(exc))
        return
    _answer(emulator.ports)
    try:
        await asyncio.get_running_loop().run_in_executor(None, sys.stdin.buffer.read)
    finally:
        await emulator.stop()


def _answer(reply: object) -> None:
    sys.stdout.buffer.write(pickle.dumps(reply))
    sys.stdout.buffer.flush()
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # anything printed later goes to stderr


def _picklable(exc: Exception) -> BaseException:
    try:
        return pickle.loads(pickle.dumps(exc))  # type: ignore[no-any-return]
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
