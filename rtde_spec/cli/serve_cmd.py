"""rtde-spec serve: a controller emulator on loopback (RTDE, primary, secondary, real-time, dashboard)."""

from __future__ import annotations

import argparse
import errno
import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT
from rtde_spec.cli.arguments import port_number, port_or_off
from rtde_spec.cli.conventions import describe
from rtde_spec.cli.live_view import add_live_arguments
from rtde_spec.cli.options import add_controller
from rtde_spec.emulator.ports import INTERPRETER_PORT
from rtde_spec.errors import UsageError
from rtde_spec.realtime import REALTIME_PORTS

if TYPE_CHECKING:
    import asyncio

    from rtde_spec.emulator.server import EmulatorConfig


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve",
        help="run a controller emulator (RTDE, primary, secondary, real-time, dashboard) for tests "
        "without a robot",
        **describe(
            "Emulates a controller from the spec: RTDE, primary, secondary, real-time and the dashboard "
            "server, an arm that runs URScript, outputs a scenario file sets. Binds to 127.0.0.1 unless told "
            "otherwise; port 0 picks a free port; the ports are printed when listening. Ctrl-C, SIGTERM or "
            "SIGHUP stops it (exit 0).",
            "rtde-spec serve",
            "rtde-spec serve --model UR10 --scenario moving.yaml",
            "rtde-spec serve --controller 3.15.8 --rtde-port 0 --primary-port 0 --secondary-port 0",
        ),
    )
    p.add_argument(
        "--host", default="127.0.0.1", metavar="ADDRESS", help="address to bind (default: 127.0.0.1)"
    )
    _add_ports(p)
    p.add_argument(
        "--programs",
        metavar="DIR",
        help="where the dashboard's `load NAME` finds programs: NAME as URScript, the .script "
        "beside NAME.urp, or NAME.urp translated (default: none, so `load` answers File not found)",
    )
    p.add_argument(
        "--external-control",
        metavar="HOST[:PORT]",
        help="the driver a .urp's External Control node (the ROS driver's URCap) asks for its "
        "program when played (default: the dashboard client that plays it, port 50002)",
    )
    p.add_argument(
        "--max-clients",
        type=int,
        default=None,
        metavar="N",
        help="connections each port takes; a further one is closed (default: 32)",
    )
    p.add_argument(
        "--model",
        metavar="ARM",
        help="arm model whose geometry and limits the robot has, e.g. UR5e, UR10 (spec/arms; "
        "default: UR5 for a CB3 version, else UR5e)",
    )
    add_controller(p, "controller version to report (default: the scenario's, else 5.15.0)")
    p.add_argument(
        "--scenario", metavar="YAML", help="YAML scenario: version and output values (default: none)"
    )
    p.add_argument(
        "--realtime-priority",
        type=int,
        metavar="PRIORITY",
        help="run the control loop at this SCHED_FIFO priority (1-99; needs CAP_SYS_NICE or root): on a "
        "loaded machine the only way to keep 500 Hz steps within 0.5 ms; refused: one log line, served "
        "as usual (default: normal priority)",
    )
    add_live_arguments(p, rtde_port=False)
    p.set_defaults(run=run)


def _add_ports(p: argparse.ArgumentParser) -> None:
    """One option per port the emulator serves, each movable (0: any free port)."""
    p.add_argument(
        "--rtde-port",
        type=port_number,
        metavar="PORT",
        default=RTDE_PORT,
        help=f"RTDE port (default: {RTDE_PORT})",
    )
    for name in ("primary", "secondary"):
        port = PRIMARY_PORTS[name]
        p.add_argument(
            f"--{name}-port",
            type=port_number,
            default=port,
            metavar="PORT",
            help=f"{name} port (default: {port})",
        )
        ro = PRIMARY_PORTS[f"{name}_read_only"]
        p.add_argument(
            f"--{name}-read-only-port",
            type=port_number,
            default=None,
            metavar="PORT",
            help=f"read-only {name} port, e.g. {ro} (default: not served)",
        )
    rt, rt_ro = REALTIME_PORTS["realtime"], REALTIME_PORTS["realtime_read_only"]
    p.add_argument(
        "--realtime-port",
        type=port_or_off,
        default=None,
        metavar="PORT",
        help=f"real-time port: the state at the control rate, URScript accepted (default: {rt} "
        "when free; -1: not served)",
    )
    p.add_argument(
        "--realtime-read-only-port",
        type=port_number,
        default=None,
        metavar="PORT",
        help=f"read-only real-time port, e.g. {rt_ro} (default: not served)",
    )
    p.add_argument(
        "--dashboard-port",
        type=port_or_off,
        default=None,
        metavar="PORT",
        help="dashboard server port (default: the controller's, 29999, when free; -1: not served). "
        "PolyScope X versions have no dashboard server",
    )
    p.add_argument(
        "--interpreter-port",
        type=port_or_off,
        default=None,
        metavar="PORT",
        help=f"interpreter socket: URScript statements for a program in interpreter mode (default: "
        f"{INTERPRETER_PORT} when free, on e-Series 5.10 and later; none before; -1: not served)",
    )


def run(args: argparse.Namespace) -> int:
    import asyncio
    import logging

    from rtde_spec.emulator.server import Emulator
    from rtde_spec.printable import SafeFormatter

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    for handler in logging.getLogger().handlers:  # what clients send is logged, never obeyed
        handler.setFormatter(SafeFormatter("%(asctime)s %(message)s"))
    config = _config(args)
    emulator = Emulator(config)

    async def main() -> None:
        stop = asyncio.Event()
        give_back = _stop_on_signals(asyncio.get_running_loop(), stop.set)
        try:
            await serve(stop)
        finally:
            give_back()  # before the loop closes its wake-up pipe, which its handlers write to

    async def serve(stop: asyncio.Event) -> None:
        await emulator.start()
        ports = ", ".join(f"{name} {port}" for name, port in emulator.ports.items())
        print(f"emulating controller {emulator.model.version} on {args.host}: {ports}", flush=True)
        view = None
        try:
            if args.foxglove is not None:  # off the loop: the loop answers the view's handshakes
                from rtde_spec.cli.live_view import LiveView

                host = "127.0.0.1" if args.host in ("0.0.0.0", "::") else args.host
                live = LiveView(host, emulator.ports["rtde"], emulator.ports["secondary"], args)
                view = await asyncio.to_thread(live.start)
            await stop.wait()
        finally:
            if view is not None:
                await asyncio.to_thread(view.stop)
            await emulator.stop()

    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        pass
    except OSError as exc:
        if exc.errno != errno.EADDRINUSE:
            raise
        where = re.search(r"\('([^']*)', (\d+)\)", str(exc))
        at = f"{where.group(1)}:{where.group(2)}" if where else args.host
        raise UsageError(
            f"cannot listen on {at}: address already in use; stop what listens there (another "
            "`rtde-spec serve`?) or give that port another number (0: any free port, printed)"
        ) from None
    return 0


def _stop_on_signals(loop: asyncio.AbstractEventLoop, stop: Callable[[], None]) -> Callable[[], None]:
    """SIGTERM and SIGHUP as callbacks of the event loop (`stop`); returns what puts the CLI's
    handlers back, to call before the loop closes.

    The CLI turns them into KeyboardInterrupt (`stop_signals`), raised wherever the loop stands;
    raised between the loop taking a task's next step off its queue and running it, it loses
    that step, and the task, cancelled then, never runs again: the likely way asyncio.run came to
    wait forever after a SIGTERM (once in five stops of a benchmark's emulator). Ctrl-C is
    asyncio.run's own: it cancels `main()`, whose `finally` stops the emulator. Where the loop
    cannot take signals (not the main thread; Windows) the CLI's handling stays."""
    import signal

    from rtde_spec.cli.stop_signals import SIGNALS, stopping

    def asked() -> None:
        stopping()  # the CLI's handler ignores the ones that come while the emulator stops
        stop()

    taken: dict[int, Any] = {}
    for name in SIGNALS:
        signum = getattr(signal, name, None)
        if signum is None:
            continue
        previous = signal.getsignal(signum)
        try:
            loop.add_signal_handler(signum, asked)
        except (NotImplementedError, RuntimeError, ValueError):
            break
        taken[signum] = previous

    def give_back() -> None:
        for signum, previous in taken.items():
            loop.remove_signal_handler(signum)
            signal.signal(signum, previous if previous is not None else signal.SIG_DFL)

    return give_back


def _config(args: argparse.Namespace) -> EmulatorConfig:
    """The emulator's configuration from the command line and --scenario (which must agree)."""
    from pathlib import Path

    from rtde_spec.emulator.controller.scenario import Scenario, load_scenario
    from rtde_spec.emulator.ports.guard import ClientLimits
    from rtde_spec.emulator.server import EmulatorConfig
    from rtde_spec.metamodel.dashboard import dashboard_spec

    scenario = load_scenario(args.scenario) if args.scenario else Scenario()
    if (
        args.controller
        and "controller" in scenario.model_fields_set
        and scenario.controller != args.controller
    ):
        raise UsageError(
            f"--controller {args.controller} and the scenario's controller: {scenario.controller} disagree; "
            "give the version once (leave out --controller, or change the scenario)",
            subject=f"--scenario {args.scenario}",
        )
    config = EmulatorConfig(
        host=args.host,
        rtde_port=args.rtde_port,
        primary_port=args.primary_port,
        secondary_port=args.secondary_port,
        primary_read_only_port=args.primary_read_only_port,
        secondary_read_only_port=args.secondary_read_only_port,
        scenario=scenario,
        controller=args.controller,
        arm=args.model,
        dashboard_port=_dashboard_port(args.dashboard_port, dashboard_spec().port),
        dashboard_optional=args.dashboard_port is None,  # the default port may be taken: then none
        programs=Path(args.programs) if args.programs else None,
        external_control=args.external_control,
        realtime_port=_dashboard_port(args.realtime_port, REALTIME_PORTS["realtime"]),
        realtime_read_only_port=args.realtime_read_only_port,
        realtime_optional=args.realtime_port is None,  # the default port may be taken: then none
        interpreter_port=_dashboard_port(args.interpreter_port, INTERPRETER_PORT),
        interpreter_optional=args.interpreter_port is None,  # the default port may be taken: then none
    )
    if args.external_control:
        from rtde_spec.emulator.controller.external_program import address

        try:
            address(args.external_control, "")
        except ValueError:
            raise UsageError(f"--external-control {args.external_control}: give HOST or HOST:PORT") from None
    if args.realtime_priority is not None:
        if not 1 <= args.realtime_priority <= 99:
            raise UsageError(f"--realtime-priority {args.realtime_priority}: give 1..99")
        config.realtime_priority = args.realtime_priority
    if args.max_clients is not None:
        config.limits = ClientLimits(max_clients=max(1, args.max_clients))
    return config


def _dashboard_port(given: int | None, default: int) -> int | None:
    """The port given, the default when none was, None when told -1 (not served)."""
    if given is None:
        return default
    return None if given < 0 else given
