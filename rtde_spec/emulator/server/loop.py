"""Run the emulated controller: the RTDE port, the primary/secondary ports, the real-time
ports, the dashboard server, the interpreter socket and the control loop.

The control loop keeps real time: each step is due at start + step / base rate
(125 Hz for CB3 versions, 500 Hz for newer). As a controller reads its inputs at the start of a
cycle and sends the cycle's state at its end, the loop wakes a lead before the due time
(`controller/clock.py`: a timerfd on Linux, no spinning), computes the step's state (the arm,
the URScript program in the time left before the due time, the scenario), and sends it at the
due time: a client's command that came before the step was computed is answered in that step's
package (ur_rtde reads the first package after it asks), and packages leave on time. The lead
follows what the steps cost: the costliest recent step (its weight wearing off by NEED_DECAY a
step) and a quarter again, at least LEAD_MIN of a step; a step whose program was preempted makes
the next ones start at LEAD_MAX (URCL's script at a spline segment's start), so a program has
most of the step when it needs it and the rest stays for the ports' reading. `Emulator` runs
in the caller's event loop; `embedded.py` runs one for code that is not asyncio (tests, the demo):
in a background thread or in a process of its own.
"""

from __future__ import annotations

import asyncio
import gc
import logging
import os
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT
from rtde_spec._generated.dashboard import DASHBOARD
from rtde_spec._generated.realtime import REALTIME_PORTS
from rtde_spec.emulator.controller.clock import StepClock
from rtde_spec.emulator.controller.faults import FaultSchedule
from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.controller.scenario import Scenario
from rtde_spec.emulator.ports.dashboard import DashboardConnection, DashboardHub
from rtde_spec.emulator.ports.guard import ClientLimits, Port
from rtde_spec.emulator.ports.interpreter_server import (
    InterpreterConnection,
    InterpreterHub,
    has_interpreter_mode,
)
from rtde_spec.emulator.ports.listener import Descriptors, Listener
from rtde_spec.emulator.ports.primary_server import PrimaryConnection, PrimaryHub
from rtde_spec.emulator.ports.realtime_server import RealtimeConnection, RealtimeHub
from rtde_spec.emulator.ports.rtde_server import RtdeConnection, RtdeHub
from rtde_spec.emulator.urscript.budgets import step_deadline
from rtde_spec.errors import UsageError
from rtde_spec.metamodel.catalogue import Catalogue

log = logging.getLogger("rtde_spec.emulator")
STATE_HZ = 10
LEAD_MIN, LEAD_MAX = 0.6, 0.8  # of a step: how long before its due time a step is computed
SEND_RESERVE = 0.05  # of a step: kept before the due time for the arm's outputs and the send
NEED_DECAY = 0.98  # per step: how fast a costly step's weight on the lead wears off


@dataclass
class EmulatorConfig:
    """The ports `rtde-spec serve` serves, on the controller's numbers: RTDE 30004, primary 30001,
    secondary 30002, real-time 30003, dashboard 29999 (the read-only ones and the interpreter socket
    off). Each moves to a free port with 0 (`emu.ports` names them) or is left out with None;
    `free_ports()` moves all."""

    host: str = "127.0.0.1"
    rtde_port: int | None = RTDE_PORT
    primary_port: int | None = PRIMARY_PORTS["primary"]
    secondary_port: int | None = PRIMARY_PORTS["secondary"]
    primary_read_only_port: int | None = None
    secondary_read_only_port: int | None = None
    scenario: Scenario = field(default_factory=Scenario)
    controller: str | None = None  # overrides the scenario's version
    arm: str | None = None  # arm model (spec/arms): default UR5 for a CB3 version, else UR5e
    dashboard_port: int | None = int(DASHBOARD["port"])  # type: ignore[call-overload]
    dashboard_optional: bool = False  # a dashboard port in use is logged and skipped, not an error
    realtime_port: int | None = REALTIME_PORTS["realtime"]
    realtime_read_only_port: int | None = None
    realtime_optional: bool = False  # a real-time port in use is logged and skipped, not an error
    # the interpreter socket (INTERPRETER_PORT, 30020, what `serve` serves): only versions with interpreter
    # mode (e-Series 5.10 on) have it. Off unless asked for: the configurations written before it
    # name each port they serve, and would all take 127.0.0.1:30020
    interpreter_port: int | None = None
    interpreter_optional: bool = False  # an interpreter port in use is logged and skipped, not an error
    programs: Path | None = None  # where the dashboard's `load` finds programs (none: "File not found")
    # HOST[:PORT] of the driver an External Control node asks for its program (the ROS driver's
    # URCap mode); None: the dashboard client that plays it, on port 50002
    external_control: str | None = None
    limits: ClientLimits = field(default_factory=ClientLimits)  # what one client may cost, per port
    # after falling this far behind (s, a stalled machine) the loop skips steps rather than
    # sending them late in a burst; None: every step is sent, late if need be
    skip_after: float | None = 0.1
    # keep how late each control step ran (s after its due time), the last this many (benchmarks)
    step_timing: int = 0
    # SCHED_FIFO priority (1-99) for the control loop's thread, as a controller runs its loop in
    # real time; needs CAP_SYS_NICE (refused: one log line, normal priority). None: normal priority
    realtime_priority: int | None = None
    # once started, move what start-up built out of the garbage collector's reach (gc.freeze), so
    # collections while serving look at the few objects the steps make, not the spec's thousands
    gc_freeze: bool = True
    # the GIL's switch interval while serving (s): another Python thread (the background parser,
    # an in-process client) holds the loop up at most this long; None leaves Python's 5 ms
    switch_interval: float | None = 0.0005

    @classmethod
    def free_ports(cls, **kw: object) -> EmulatorConfig:
        """Every port `rtde-spec serve` serves (RTDE, primary, secondary, real-time, dashboard, interpreter),
        each on a free port (`emu.ports` names them); a keyword moves or drops one (None).
        Tests running side by side use this: the plain defaults are the controller's fixed ports.
        """
        ports: dict[str, object] = {
            "rtde_port": 0, "primary_port": 0, "secondary_port": 0, "realtime_port": 0, "dashboard_port": 0,
            "interpreter_port": 0,
        }  # fmt: skip
        return cls(**{**ports, **kw})  # type: ignore[arg-type]


class Emulator:
    def __init__(self, config: EmulatorConfig | None = None, catalogue: Catalogue | None = None) -> None:
        self.config = config or EmulatorConfig()
        for name, port in vars(self.config).items():  # 70000 was served on 4464, "x" a gaierror
            if name.endswith("_port") and port is not None and not (type(port) is int and 0 <= port <= 65535):
                raise UsageError(f"{name} must be a TCP port 0..65535 (0: a free one) or None, not {port!r}")
        cat = catalogue or Catalogue.default()
        version = self.config.controller or self.config.scenario.controller
        arm = self.config.arm or ("UR5" if cat.line_of(version).id == "cb3" else "UR5e")
        self.model = ControllerModel(version, cat, self.config.scenario.functions(cat), model=arm)
        self.model.calibrated = self.config.scenario.calibrated
        self.rtde = RtdeHub(self.model)
        self.primary = PrimaryHub(self.model)
        self.dashboard = DashboardHub(
            self.model, self.config.programs, external_control=self.config.external_control
        )
        self.realtime = RealtimeHub(self.model, self.primary)
        self.interpreter = InterpreterHub(self.model)
        self.faults = FaultSchedule(self.config.scenario.faults, self.model)
        self._silenced = False
        self.servers: list[Listener] = []
        self.descriptors = Descriptors()  # one held in reserve; running out logged once
        self.ports: dict[str, int] = {}
        self.clients: dict[str, Port] = {}  # port name -> its connections, under the limits
        self._loop_task: asyncio.Task[None] | None = None
        self._clock: StepClock | None = None
        self._serving = False
        self.late_steps = 0
        # steps at whose end a program thread was still preempted (its work went on in the next)
        self.cut_steps = 0
        # per step, when step_timing is set: how late it woke, how late its packages were all
        # written, and how long it was busy (sending, then the next step's arm, program, scenario)
        self.step_lateness: deque[float] = deque(maxlen=max(1, self.config.step_timing))
        self.step_busy: deque[float] = deque(maxlen=max(1, self.config.step_timing))
        self.step_sent: deque[float] = deque(maxlen=max(1, self.config.step_timing))  # s after due

    async def start(self) -> None:
        loop = asyncio.get_running_loop()
        c = self.config
        if c.rtde_port is not None:
            clients = self._port("rtde")
            await self._listen("rtde", c.rtde_port, lambda: RtdeConnection(self.rtde, clients))
        for name, port, read_only in (
            ("primary", c.primary_port, False),
            ("secondary", c.secondary_port, False),
            ("primary_read_only", c.primary_read_only_port, True),
            ("secondary_read_only", c.secondary_read_only_port, True),
        ):
            if port is not None:
                await self._listen(name, port, self._primary_factory(name, read_only))
        for name, port, read_only in (
            ("realtime", c.realtime_port, False),
            ("realtime_read_only", c.realtime_read_only_port, True),
        ):
            if port is not None:
                await self._optional(name, port, self._realtime_factory(name, read_only), c.realtime_optional)
        if c.dashboard_port is not None:
            if self.dashboard.available:
                clients = self._port("dashboard")
                try:
                    await self._listen(
                        "dashboard", c.dashboard_port, lambda: DashboardConnection(self.dashboard, clients)
                    )
                except OSError as exc:
                    if not c.dashboard_optional:
                        raise
                    log.warning("no dashboard server: port %d: %s", c.dashboard_port, exc.strerror)
            else:
                log.info("no dashboard server: controller %s has none", self.model.version)
        if c.interpreter_port is not None and has_interpreter_mode(self.model):
            clients = self._port("interpreter")
            factory = lambda: InterpreterConnection(self.interpreter, clients)  # noqa: E731
            await self._optional("interpreter", c.interpreter_port, factory, c.interpreter_optional)
        elif c.interpreter_port is not None:
            log.info("no interpreter socket: controller %s has no interpreter mode", self.model.version)
        if c.realtime_priority is not None:
            _real_time(c.realtime_priority)
        _serving(+1, c)
        self._serving = True
        self._clock = StepClock()  # its timerfd before the reserve: steps on time matter more
        self._loop_task = loop.create_task(self._control_loop(self._clock))
        self.descriptors.start()

    def _port(self, name: str) -> Port:
        self.clients[name] = Port(name, self.config.limits)
        return self.clients[name]

    async def _optional(self, name: str, port: int, factory, optional: bool) -> None:  # type: ignore[no-untyped-def]
        """Listen; a port in use is an error, or (optional) one log line and no such server."""
        try:
            await self._listen(name, port, factory)
        except OSError as exc:
            if not optional:
                raise
            self.clients.pop(name, None)
            log.warning("no %s server: port %d: %s", name, port, exc.strerror)

    def _realtime_factory(self, name: str, read_only: bool):  # type: ignore[no-untyped-def]
        port = self._port(name)
        return lambda: RealtimeConnection(self.realtime, port, self.ports[name], read_only)

    def _primary_factory(self, name: str, read_only: bool):  # type: ignore[no-untyped-def]
        port = self._port(name)
        messages = name.startswith("primary")
        return lambda: PrimaryConnection(self.primary, port, self.ports[name], read_only, messages)

    async def _listen(self, name: str, port: int, factory) -> None:  # type: ignore[no-untyped-def]
        """Listen with our own accept loop, not asyncio's: out of file descriptors it floods the
        log with tracebacks and leaves clients waiting (ports/listener.py)."""
        server = await Listener.open(self.config.host, port, factory, self.descriptors)
        self.servers.append(server)
        self.ports[name] = server.port
        log.info("%s on %s:%d", name, self.config.host, self.ports[name])

    async def _control_loop(self, clock: StepClock) -> None:
        try:
            await self._steps(clock)
        finally:
            clock.close()

    async def _steps(self, clock: StepClock) -> None:
        base = self.model.base_hz
        state_every = max(1, base // STATE_HZ)
        timing = self.config.step_timing
        skip_after = self.config.skip_after
        model = self.model
        period = 1.0 / base
        lead, need = LEAD_MIN * period, 0.0
        start = time.perf_counter()
        step = 0
        while True:
            step += 1
            due = start + step / base
            await clock.until(due - lead)
            # inputs already in the sockets are read before the step is computed, as a controller
            # reads them at a cycle's start: one loop turn takes what was readable when it woke,
            # the second what came in while this process waited for a core (a loaded machine)
            await asyncio.sleep(0)
            await asyncio.sleep(0)
            woke = time.perf_counter()
            if skip_after is not None and woke - due > skip_after:  # skip, don't burst
                self.late_steps += 1
                if self.late_steps == 1:
                    log.warning(
                        "control loop %.0f ms behind: it skips steps (a stalled machine; in an "
                        "EmulatorThread, another thread of the process holding the GIL)",
                        (woke - due) * 1000,
                    )
                step = max(step, int((woke - start) * base))
                due = start + step / base
            if timing:
                self.step_lateness.append(woke - (due - lead))
            with step_deadline(due - SEND_RESERVE * period) as work:  # this step's state, now
                model.tick(step)
                self.faults.apply(model.time)
            busy = time.perf_counter() - woke
            if work.cut:
                self.cut_steps += 1
            need = period if work.cut else max(busy, need * NEED_DECAY)
            lead = min(LEAD_MAX, max(LEAD_MIN, 1.25 * need / period + SEND_RESERVE)) * period
            await clock.until(due)
            if not self._network(self.faults.silent(model.time)):  # a network drop: nothing goes out
                self.rtde.send_outputs(step)
                self.realtime.send()
                if step % state_every == 0:
                    self.primary.broadcast_state()
                    now = time.monotonic()
                    for port in self.clients.values():
                        port.check(now)
            if timing:
                sent = time.perf_counter() - due
                self.step_sent.append(sent)  # its packages are out
                self.step_busy.append(busy + max(0.0, sent))

    def _network(self, down: bool) -> bool:
        """Pause or resume reading from every client as a network drop begins or ends; True while down."""
        if down != self._silenced:
            self._silenced = down
            log.warning("scenario: network %s", "down" if down else "up again")
            for port in self.clients.values():
                for conn in port.connections:
                    transport = conn.transport
                    if transport is not None and not transport.is_closing():
                        (transport.pause_reading if down else transport.resume_reading)()
        return down

    async def stop(self) -> None:
        if self._loop_task is not None:
            self._loop_task.cancel()
        if self._serving:
            self._serving = False
            _serving(-1, self.config)
        for server in self.servers:
            server.close()
        for port in self.clients.values():
            for conn in list(port.connections):
                if conn.transport is not None:
                    conn.transport.abort()
        for server in self.servers:
            await server.wait_closed()
        if self._clock is not None:  # a loop task cancelled before it ran never closed it
            self._clock.close()
        self.descriptors.release()

    async def serve_forever(self) -> None:
        await self.start()
        try:
            await asyncio.Event().wait()
        finally:
            await self.stop()


_SERVING = {"count": 0, "switch_interval": 0.0, "frozen": 0}


def _serving(change: int, config: EmulatorConfig) -> None:
    """Process-wide settings while any emulator serves (several may run in one test process):
    the GIL's switch interval and gc.freeze; the last one stopped puts them back."""
    state = _SERVING
    if change > 0 and state["count"] == 0:
        state["switch_interval"] = sys.getswitchinterval()
        if config.switch_interval is not None:
            sys.setswitchinterval(min(config.switch_interval, sys.getswitchinterval()))
    if change > 0 and config.gc_freeze and not state["frozen"]:
        gc.freeze()  # no collection first (it costs a big test process 0.1 s): unfrozen at the end
        state["frozen"] += 1
    state["count"] += change
    if change < 0 and state["count"] == 0:
        sys.setswitchinterval(state["switch_interval"])
        if state["frozen"]:
            state["frozen"] = 0
            gc.unfreeze()  # what became garbage meanwhile is collectable again


def _real_time(priority: int) -> None:
    """SCHED_FIFO for the calling thread (the control loop's), or one log line saying why not."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))  # type: ignore[attr-defined,unused-ignore]
    except (AttributeError, OSError, ValueError) as exc:
        log.warning("control loop at normal priority: SCHED_FIFO %d refused (%s)", priority, exc)
    else:
        log.info("control loop at SCHED_FIFO priority %d", priority)
