"""rtde-spec watch: a robot's primary/secondary stream, live, as a person or a pipe wants it."""

from __future__ import annotations

import argparse
import datetime
import json
import sys
import time
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import PRIMARY_PORTS
from rtde_spec.cli.common import existing_file
from rtde_spec.errors import RtdeConnectionError, UsageError

if TYPE_CHECKING:
    from rtde_spec.primary.base import RobotStateMessage
    from rtde_spec.primary.events import StateChanges


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "watch",
        help="watch a controller's primary/secondary port live: messages, mode changes, URScript",
        description="One line per robot message (version, errors, safety, text, runtime exceptions) "
        "and the robot's modes whenever they change; --json for every message as a JSON line. "
        "Ctrl-C stops it.",
    )
    p.add_argument("--host", required=True, help="controller address (required)")
    secondary = PRIMARY_PORTS["secondary"]
    p.add_argument(
        "--port",
        type=int,
        default=secondary,
        help=f"primary/secondary port: {', '.join(map(str, PRIMARY_PORTS.values()))} (default: {secondary})",
    )
    p.add_argument("--json", action="store_true", help="every message as a JSON line (default: text)")
    p.add_argument(
        "--every", action="store_true", help="also a line per Robot State: joints, TCP pose (default: off)"
    )
    p.add_argument(
        "--script",
        metavar="FILE",
        help="send this URScript file ('-': stdin) once connected, primary/secondary ports (default: none)",
    )
    stop = p.add_mutually_exclusive_group()
    stop.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: Ctrl-C)")
    stop.add_argument("--count", type=int, metavar="N", help="stop after N messages (default: Ctrl-C)")
    p.add_argument(
        "--timeout", type=float, default=5.0, help="seconds without a message that are an error (default: 5)"
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from rtde_spec.cli.primary_output import as_json
    from rtde_spec.primary.client import PrimaryClient
    from rtde_spec.primary.events import StateChanges

    script = _script(args.script) if args.script else None
    client = PrimaryClient(args.host, args.port, timeout=args.timeout)
    if script is not None and client.read_only:
        client.send_script(script)  # raises the read-only error before connecting
    changes = StateChanges()
    seen = 0
    deadline = time.monotonic() + args.duration if args.duration is not None else None
    with client:
        print(f"watching {client.where}", file=sys.stderr)
        if script is not None:
            client.send_script(script)
            print(f"sent {len(script.splitlines())} line(s) of URScript", file=sys.stderr)
        for _, message in client:
            now = datetime.datetime.now()
            if args.json:
                print(json.dumps({"received": now.isoformat(), **as_json(message)}), flush=True)
            else:
                for kind, text in _lines(message, changes, args.every):
                    print(f"{now:%H:%M:%S.%f}"[:-3] + f"  {kind:8s} {text}", flush=True)
            seen += 1
            if (args.count is not None and seen >= args.count) or (
                deadline is not None and time.monotonic() >= deadline
            ):
                return 0
    raise RtdeConnectionError("the controller closed the connection", subject=client.where)


def _lines(message: Any, changes: StateChanges, every: bool) -> list[tuple[str, str]]:
    """(kind, text) lines for one message: robot messages always, Robot State when modes change."""
    from rtde_spec.primary.base import RobotStateMessage
    from rtde_spec.primary.events import message_parts

    if not isinstance(message, RobotStateMessage):
        return [message_parts(message) or ("message", "")]
    out = []
    changed = changes.describe(message)
    if changed:
        out.append(("state", changed))
    if every:
        out.append(("pose", _pose(message)))
    return out


def _pose(message: RobotStateMessage) -> str:
    """Joint positions and TCP pose, the two things a Robot State is most often read for."""
    parts = []
    joints = message.get("joint_data")
    if joints is not None:
        parts.append("q [rad] " + " ".join(f"{j.q_actual:.4f}" for j in joints.joints))
    cart = message.get("cartesian_info")
    if cart is not None:
        pose = (cart.x, cart.y, cart.z, cart.rx, cart.ry, cart.rz)
        parts.append("tcp [m, rad] " + " ".join(f"{v:.4f}" for v in pose))
    return " · ".join(parts) or "(no joint data or cartesian info)"


def _script(arg: str) -> str:
    if arg == "-":
        return sys.stdin.read()
    path = existing_file(arg)
    if path is None:
        raise UsageError("URScript file not found", subject=f"file {arg}")
    return path.read_text(encoding="utf-8")
