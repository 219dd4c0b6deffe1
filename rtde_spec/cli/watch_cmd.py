"""rtde-spec watch: a robot's primary/secondary stream, live, as a person or a pipe wants it.

With --foxglove, the same messages (and, over RTDE, the outputs of --rtde-fields) are
also served to the Foxglove app over a WebSocket, with the tool's frame moving in 3D.
"""

from __future__ import annotations

import argparse
import datetime
import json
import sys
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import PRIMARY_PORTS
from rtde_spec.cli.arguments import existing_file
from rtde_spec.cli.conventions import describe, plural
from rtde_spec.cli.live_view import add_live_arguments, start_live, subscribe_rtde
from rtde_spec.cli.options import add_connection
from rtde_spec.errors import RtdeConnectionError, RtdeSpecError, UsageError

if TYPE_CHECKING:
    from rtde_spec.primary.client import PrimaryClient
    from rtde_spec.primary.events import StateChanges
    from rtde_spec.rtde.client import RtdeClient
    from rtde_spec.wire.primary_base import RobotStateMessage


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "watch",
        help="watch a controller's primary/secondary port live: messages, mode changes, URScript",
        **describe(
            "One line per robot message (version, errors, safety, text, runtime exceptions) and the "
            "robot's modes whenever they change; --jsonl for every message as a JSON line. Ctrl-C stops "
            "it, or --count LINES, --duration SECONDS; with --script, the program's end does. --foxglove "
            "serves the same to the Foxglove app.",
            "rtde-spec watch --host 127.0.0.1 --count 3",
            "rtde-spec watch --host 127.0.0.1 --script move.script",
            "rtde-spec watch --host 127.0.0.1 --jsonl --duration 10 > messages.jsonl",
            "rtde-spec watch --host 127.0.0.1 --foxglove 8765",
        ),
    )
    ports = ", ".join(map(str, PRIMARY_PORTS.values()))
    add_connection(
        p,
        PRIMARY_PORTS["primary"],  # the messages come only there; 30002 sends Robot State and Version
        f"primary/secondary port: {ports}",
        "seconds without a message that are an error",
    )
    p.add_argument(
        "--jsonl", action="store_true", dest="json", help="every message as a JSON line (default: text)"
    )
    p.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # the old spelling of --jsonl
    p.add_argument(
        "--every", action="store_true", help="also a line per Robot State: joints, TCP pose (default: off)"
    )
    p.add_argument(
        "--script",
        metavar="FILE",
        help="send this URScript file ('-': stdin) once connected, primary/secondary ports (default: none)",
    )
    stop = p.add_mutually_exclusive_group()
    stop.add_argument(
        "--duration", type=float, metavar="SECONDS", help="stop after SECONDS seconds (default: Ctrl-C)"
    )
    stop.add_argument(
        "--count", type=int, metavar="LINES",
        help="stop after printing LINES lines (with --jsonl: messages) (default: Ctrl-C; with --script: "
        "the program's end)",
    )  # fmt: skip
    stop.add_argument(
        "--until-stopped", action="store_true",
        help="with --script, go on after the program ends, until Ctrl-C (default: stop at its end)",
    )  # fmt: skip
    add_live_arguments(p)
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
    program = ProgramEnd(waits=args.count is None and args.duration is None and not args.until_stopped)
    seen = 0
    deadline = time.monotonic() + args.duration if args.duration is not None else None
    live = start_live(args)
    rtde: RtdeClient | None = None
    try:
        with client:
            print(f"watching {client.where}", file=sys.stderr)
            if args.port in _STATE_ONLY:
                print(
                    f"note: port {args.port} sends only Robot State and the Version message: errors, "
                    f"texts and runtime exceptions come on {_MESSAGES[args.port]}",
                    file=sys.stderr,
                )
            if live is not None:
                rtde = subscribe_rtde(args, live)
            if script is not None:
                client.send_script(script)
                print(f"sent {plural(len(script.splitlines()), 'line')} of URScript", file=sys.stderr)
            for message in _first_checked(client, args):
                now = datetime.datetime.now()
                if live is not None:
                    live.publish_row(as_json(message), protocol="primary")
                if args.json:
                    print(json.dumps({"received": now.isoformat(), **as_json(message)}), flush=True)
                    seen += 1
                else:  # --count counts the lines printed, not the Robot States that print none
                    for kind, text in _lines(message, changes, args.every):
                        print(f"{now:%H:%M:%S.%f}"[:-3] + f"  {kind:8s} {text}", flush=True)
                        seen += 1
                        if args.count is not None and seen >= args.count:
                            break
                if (args.count is not None and seen >= args.count) or (
                    deadline is not None and time.monotonic() >= deadline
                ):
                    return 0
                if script is not None and program.ended(message):
                    print("the program ended", file=sys.stderr)
                    return 0
    finally:
        if rtde is not None:
            rtde.close()
        if live is not None:
            live.close()
    raise RtdeConnectionError("the controller closed the connection", subject=client.where)


_MESSAGES = {PRIMARY_PORTS["secondary"]: PRIMARY_PORTS["primary"]}
_MESSAGES[PRIMARY_PORTS["secondary_read_only"]] = PRIMARY_PORTS["primary_read_only"]
_STATE_ONLY = frozenset(_MESSAGES)  # the secondary ports (the primary/secondary document)


class ProgramEnd:
    """With --script and no other end: done once the program has stopped (the key message
    PROGRAM_XXX_STOPPED, a runtime exception, or Robot State's is_program_running going true,
    then false), so the output of the whole program shows."""

    def __init__(self, waits: bool) -> None:
        self.waits = waits
        self.running = False

    def ended(self, message: Any) -> bool:
        if not self.waits:
            return False
        name = getattr(message, "NAME", "")
        if name == "runtime_exception_message" or (
            name == "key_message" and getattr(message, "robot_message_title", "") == "PROGRAM_XXX_STOPPED"
        ):
            return True  # the controller says so (a program can start and stop between two states)
        mode = message.get("robot_mode_data") if hasattr(message, "get") else None
        running = getattr(mode, "is_program_running", None)
        if not self.waits or running is None:
            return False
        was, self.running = self.running, bool(running)
        return was and not self.running


def _first_checked(client: PrimaryClient, args: argparse.Namespace) -> Iterator[Any]:
    """The client's messages; when none comes (a time-out, bytes that are no primary message),
    the error says what listens on the port instead if it is not the primary interface."""
    messages = iter(client)
    try:
        first = next(messages)
    except StopIteration:
        return
    except (RtdeSpecError, TimeoutError) as exc:
        client.close()
        from rtde_spec.cli.port_probe import handshake_error

        raise handshake_error(args, "primary", exc)  # noqa: B904 (the cause is set)
    yield first
    yield from messages


def _lines(message: Any, changes: StateChanges, every: bool) -> list[tuple[str, str]]:
    """(kind, text) lines for one message: robot messages always, Robot State when modes change."""
    from rtde_spec.primary.events import message_parts
    from rtde_spec.wire.primary_base import RobotStateMessage

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
