"""rtde-spec serve: a controller emulator on loopback (RTDE, primary and secondary ports)."""

from __future__ import annotations

import argparse

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT
from rtde_spec.cli.common import controller_version


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve",
        help="run a controller emulator (RTDE, primary, secondary) for tests without a robot",
        description="Emulate a controller from the spec. Binds to 127.0.0.1 unless told otherwise; "
        "port 0 picks a free port; the ports are printed when listening. Ctrl-C stops it.",
    )
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default: 127.0.0.1)")
    p.add_argument("--rtde-port", type=int, default=RTDE_PORT, help=f"RTDE port (default: {RTDE_PORT})")
    for name in ("primary", "secondary"):
        port = PRIMARY_PORTS[name]
        p.add_argument(f"--{name}-port", type=int, default=port, help=f"{name} port (default: {port})")
        ro = PRIMARY_PORTS[f"{name}_read_only"]
        p.add_argument(
            f"--{name}-read-only-port",
            type=int,
            default=None,
            help=f"read-only {name} port, e.g. {ro} (default: not served)",
        )
    p.add_argument(
        "--controller",
        metavar="VERSION",
        type=controller_version,
        help="controller version to report (default: the scenario's, else 5.15.0)",
    )
    p.add_argument(
        "--scenario", metavar="FILE", help="YAML scenario: version and output values (default: none)"
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import asyncio
    import logging

    from rtde_spec.emulator.scenario import Scenario, load_scenario
    from rtde_spec.emulator.server import Emulator, EmulatorConfig

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    config = EmulatorConfig(
        host=args.host,
        rtde_port=args.rtde_port,
        primary_port=args.primary_port,
        secondary_port=args.secondary_port,
        primary_read_only_port=args.primary_read_only_port,
        secondary_read_only_port=args.secondary_read_only_port,
        scenario=load_scenario(args.scenario) if args.scenario else Scenario(),
        controller=args.controller,
    )
    emulator = Emulator(config)

    async def main() -> None:
        await emulator.start()
        ports = ", ".join(f"{name} {port}" for name, port in emulator.ports.items())
        print(f"emulating controller {emulator.model.version} on {args.host}: {ports}", flush=True)
        try:
            await asyncio.Event().wait()
        finally:
            await emulator.stop()

    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        pass
    return 0
