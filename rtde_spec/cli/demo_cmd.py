"""rtde-spec demo: decode the embedded example session and summarise the catalogue.

It needs no robot: the session is a file shipped with the package.
"""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

from rtde_spec.cli.arguments import catalogue_for
from rtde_spec.cli.conventions import describe
from rtde_spec.cli.inputs import parse_hex
from rtde_spec.output.text import table

if TYPE_CHECKING:
    from rtde_spec.metamodel.catalogue import Catalogue
    from rtde_spec.rtde.codec import Sender

EXAMPLE = "rtde_session_v2.txt"
PRIMARY_EXAMPLE = "primary_stream.hex"
RECIPE_EXAMPLE = "ur_rtde_default_outputs.txt"
SHOWCASE_VERSIONS = ("3.15.8", "5.12.2", "10.11.0")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "demo",
        help="record from the built-in controller emulator, plot it (no robot needed)",
        **describe(
            "Starts the controller emulator on loopback, sends it a short motion program (movej, movel, "
            "movej home) on its primary port, records the joints through the RTDE client meanwhile, "
            "writes a CSV and a PNG plot of the moving joints (in a new temporary folder, or -o), prints "
            "a summary. --offline decodes embedded example bytes instead.",
            "rtde-spec demo",
            "rtde-spec demo -o my-demo/ --seconds 5",
            "rtde-spec demo --offline",
        ),
    )
    p.add_argument("--offline", action="store_true", help="decode embedded examples only (default: online)")
    p.add_argument(
        "--seconds", type=float, default=3.0, metavar="SECONDS", help="how long to record (default: 3)"
    )
    p.add_argument(
        "-o", "--output", type=Path, metavar="FOLDER",
        help="folder for joints.csv and joints.png (default: a new temporary folder, printed)",
    )  # fmt: skip
    p.add_argument("--out", type=Path, dest="output", help=argparse.SUPPRESS)  # deprecated spelling
    p.add_argument(
        "--session",
        type=Path,
        metavar="FILE",
        help="with --offline: a session file of your own (default: the embedded one)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if args.offline or args.session:
        return run_offline(args)
    from rtde_spec.cli.demo_online import run_online

    return run_online(args)


def read_session(text: str) -> list[tuple[Sender, bytes, str]]:
    """Lines of 'sender hex  # note' -> (sender, bytes, note)."""
    out = []
    for number, line in enumerate(text.splitlines(), 1):
        body, _, note = line.partition("#")
        if not body.strip():
            continue
        parts = body.split()
        if len(parts) != 2 or parts[0] not in ("client", "controller"):
            raise ValueError(f"session line {number}: expected 'client|controller HEX'")
        sender: Sender = "client" if parts[0] == "client" else "controller"
        out.append((sender, parse_hex(parts[1]), note.strip()))
    return out


def run_offline(args: argparse.Namespace) -> int:
    from rtde_spec.output.describe import describe
    from rtde_spec.rtde.session import SessionDecoder

    catalogue = catalogue_for(args)
    if args.session:
        text = args.session.read_text(encoding="utf-8")
        source = str(args.session)
    else:
        text = resources.files("rtde_spec.examples").joinpath(EXAMPLE).read_text("utf-8")
        source = f"embedded example {EXAMPLE}"
    session = SessionDecoder(catalogue=catalogue)
    rows = []
    for sender, package, _note in read_session(text):
        decoded = session.feed(sender, package)
        msg = decoded.message
        if decoded.values is not None:
            fields = {**msg.fields(), **decoded.values}
            fields.pop("payload")
        else:
            fields = msg.fields()
        details = ", ".join(f"{k}={describe(v, msg.ENUMS.get(k))}" for k, v in fields.items())
        if decoded.note:
            details += f"  [{decoded.note}]"
        rows.append([sender, chr(msg.PACKAGE_TYPE), msg.NAME, len(package), details])
    print(f"Decoded {len(rows)} packages of the {source}:\n")
    print(table(["from", "type", "package", "bytes", "fields"], rows, max_width=160))
    print("\nFields available per controller version:\n")
    summary = []
    for version in SHOWCASE_VERSIONS:
        line = catalogue.line_of(version)
        summary.append(
            [
                version,
                line.name,
                len(catalogue.fields("input", version)),
                len(catalogue.fields("output", version)),
                line.rtde_max_frequency,
            ]
        )
    print(table(["controller", "line", "inputs", "outputs", "max Hz"], summary))
    _primary_part()
    _recipe_part(catalogue)
    print("\nNext: rtde-spec fields --controller 5.12.2, rtde-spec decode HEX --from controller,")
    print("      rtde-spec decode --protocol primary FILE, rtde-spec validate RECIPE --controller 5.12.2")
    return 0


def _example(name: str) -> str:
    return resources.files("rtde_spec.examples").joinpath(name).read_text("utf-8")


def _primary_part() -> None:
    """Decode the embedded primary-interface stream, in small TCP-like chunks."""
    from rtde_spec.output.describe import describe
    from rtde_spec.primary.codec import PrimaryStreamDecoder
    from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

    text = "".join(line for line in _example(PRIMARY_EXAMPLE).splitlines() if not line.startswith("#"))
    data = parse_hex(text)
    decoder = PrimaryStreamDecoder()
    messages = []
    for start in range(0, len(data), 100):  # arbitrary read boundaries
        messages += decoder.feed(data[start : start + 100])
    decoder.close()
    print(
        f"\nPrimary interface: {len(data)} bytes in 100-byte reads -> {len(messages)} messages "
        f"(controller {decoder.version}):\n"
    )
    rows = []
    for offset, message in messages:
        if isinstance(message, RobotStateMessage):
            names = ", ".join(getattr(s, "NAME", "?") for s in message.sub_packages)
            mode = message["robot_mode_data"]
            q = [round(j.q_actual, 3) for j in message["joint_data"].joints]
            detail = f"{len(message.sub_packages)} sub-packages ({names}); robot_mode="
            detail += f"{describe(mode.robot_mode, 'RobotMode')}, q_actual={q}"
        elif isinstance(message, PrimaryPart):
            detail = ", ".join(f"{k}={v!r}" for k, v in message.values().items() if k != "timestamp")
        else:
            detail = repr(message)
        rows.append([offset, message.NAME, detail])
    print(table(["offset", "message", "content"], rows, max_width=150))


def _recipe_part(catalogue: Catalogue) -> None:
    """Validate ur_rtde's default output recipe for three controller lines."""
    from rtde_spec.recipes.model import Recipe
    from rtde_spec.recipes.validation import validate_recipes

    recipe = Recipe(
        tuple(
            n.strip() for n in _example(RECIPE_EXAMPLE).splitlines() if n.strip() and not n.startswith("#")
        ),
        direction="output",
    )
    print(f"\nValidating ur_rtde's default {len(recipe.names)}-field output recipe at 500 Hz:\n")
    rows = []
    for version in SHOWCASE_VERSIONS:
        report = validate_recipes([recipe], controller=version, frequency=500, catalogue=catalogue)
        errors = [p for p in report.all_problems if p.severity == "error"]
        first = f"{errors[0].field}: {errors[0].message}" if errors else ""
        rows.append([version, "valid" if report.valid else "INVALID", len(errors), first])
    print(table(["controller", "result", "errors", "first error"], rows, max_width=110))
