"""The live view in Foxglove: its options, and the RTDE outputs and primary messages it serves.

`watch --foxglove` and `serve --foxglove` (against the emulator's own ports) share it.
"""

from __future__ import annotations

import argparse
import sys
import threading
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import RTDE_PORT
from rtde_spec.errors import UsageError
from rtde_spec.output.foxglove_live import DEFAULT_PORT

if TYPE_CHECKING:
    from rtde_spec.output.foxglove_live import LivePublisher
    from rtde_spec.rtde.client import RtdeClient

# What a live view is usually opened for: joints, tool pose and load, modes. Fields the
# controller's version lacks are left out of this default (an explicit list is taken as given).
LIVE_FIELDS = (
    "timestamp", "actual_q", "actual_qd", "target_q", "actual_current", "joint_temperatures",
    "actual_TCP_pose", "actual_TCP_speed", "actual_TCP_force", "speed_scaling",
    "robot_mode", "safety_mode", "runtime_state",
)  # fmt: skip


def add_live_arguments(p: argparse.ArgumentParser, rtde_port: bool = True) -> None:
    """--foxglove [PORT] and what it serves (watch, and serve for its own ports: no --rtde-port)."""
    live = p.add_argument_group("live view in Foxglove")
    live.add_argument(
        "--foxglove",
        nargs="?",
        type=int,
        const=DEFAULT_PORT,
        metavar="PORT",
        help=f"serve the messages to the Foxglove app on ws://HOST:PORT (PORT default {DEFAULT_PORT}; "
        "0: any free port, printed) (default: off)",
    )
    live.add_argument(
        "--foxglove-host",
        default="127.0.0.1",
        metavar="ADDRESS",
        help="address the live view listens on; 0.0.0.0 for other machines (default: 127.0.0.1)",
    )
    live.add_argument(
        "--rtde-fields",
        metavar="NAMES",
        default=",".join(LIVE_FIELDS),
        help="with --foxglove, also subscribe these RTDE outputs (comma list; 'none': primary only) "
        "(default: joints, TCP pose/speed/force, currents, temperatures, modes)",
    )
    if rtde_port:
        live.add_argument(
            "--rtde-port",
            type=int,
            default=RTDE_PORT,
            metavar="PORT",
            help=f"RTDE port (default: {RTDE_PORT})",
        )
    live.add_argument(
        "--rtde-frequency",
        type=float,
        default=125.0,
        metavar="HZ",
        help="RTDE output rate in Hz (default: 125)",
    )


def start_live(args: argparse.Namespace) -> LivePublisher | None:
    """The Foxglove server of --foxglove, started (its address on stderr), or None."""
    if args.foxglove is None:
        return None
    if not 0 <= args.foxglove <= 65535:
        raise UsageError(f"--foxglove {args.foxglove}: a port 0..65535 (0: any free port)")
    from rtde_spec.output.foxglove_live import LivePublisher

    live = LivePublisher(args.foxglove, args.foxglove_host)
    print(
        f"live view for Foxglove on {live.url} (Foxglove: Open connection, Foxglove WebSocket)",
        file=sys.stderr,
    )
    return live


def subscribe_rtde(args: argparse.Namespace, live: LivePublisher) -> RtdeClient | None:
    """An RTDE client whose outputs (--rtde-fields) go to the live view from its reader thread."""
    from rtde_spec.rtde.client import RtdeClient

    names = [n.strip() for n in args.rtde_fields.split(",") if n.strip()]
    if not names or names == ["none"]:
        return None
    rtde = RtdeClient(args.host, args.rtde_port, timeout=args.timeout)
    try:
        rtde.connect()
        if args.rtde_fields == ",".join(LIVE_FIELDS) and rtde.controller_version is not None:
            names = _available(names, str(rtde.controller_version))
        rtde.setup_outputs(names, args.rtde_frequency)
        recipe_id = rtde.core.output_recipe_id
        rtde.on_data(lambda record: live.publish_record(record, recipe_id))
        rtde.start()
    except BaseException:
        rtde.close()
        raise
    print(
        f"live view: {len(names)} RTDE outputs at {args.rtde_frequency:g} Hz from {rtde.where}",
        file=sys.stderr,
    )
    return rtde


def _available(names: list[str], controller: str) -> list[str]:
    from rtde_spec.metamodel.catalogue import Catalogue

    cat = Catalogue.default()
    return [
        n for n in names if (info := cat.get(n, "output")) is not None and cat.available(info, controller)
    ]


class LiveView:
    """A controller's RTDE outputs and primary/secondary messages served to Foxglove, each read in
    its own thread: what `serve --foxglove` runs against its own ports (start and stop it from a
    thread other than the emulator's event loop, which must answer the handshakes meanwhile)."""

    def __init__(self, host: str, rtde_port: int, primary_port: int, args: argparse.Namespace) -> None:
        self.host, self.rtde_port, self.primary_port, self.args = host, rtde_port, primary_port, args
        self.live: LivePublisher | None = None
        self._rtde: RtdeClient | None = None
        self._stop = threading.Event()
        self._reader: threading.Thread | None = None
        self._timeout = float(getattr(args, "timeout", 5.0))

    def start(self) -> LiveView:
        from rtde_spec.primary.client import PrimaryClient

        self.live = start_live(self.args)
        if self.live is None:
            return self
        try:
            own = {"host": self.host, "rtde_port": self.rtde_port, "timeout": self._timeout}
            options = argparse.Namespace(**{**vars(self.args), **own})
            self._rtde = subscribe_rtde(options, self.live)
            client = PrimaryClient(self.host, self.primary_port, timeout=self._timeout).connect()
        except BaseException:
            self.stop()
            raise
        self._reader = threading.Thread(
            target=self._primary, args=(client,), name="live-primary", daemon=True
        )
        self._reader.start()
        return self

    def _primary(self, client: Any) -> None:
        from rtde_spec.cli.primary_output import as_json

        live = self.live
        assert live is not None
        try:
            for message in client:
                if self._stop.is_set():
                    break
                live.publish_row(as_json(message), protocol="primary")
        except Exception:  # the controller went away: the view keeps what it had
            pass
        finally:
            client.close()

    def stop(self) -> None:
        self._stop.set()
        if self._rtde is not None:
            self._rtde.close()
        if self._reader is not None:
            self._reader.join(2 * self._timeout)
        if self.live is not None:
            self.live.close()
