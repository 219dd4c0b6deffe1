"""rtde-spec demo: decode the embedded example session and summarise the catalogue.

It needs no robot: the session is a file shipped with the package.
"""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

from ..codec import Sender
from ..describe import describe
from ..session_decoder import SessionDecoder
from .render import parse_hex, table

EXAMPLE = "rtde_session_v2.txt"
SHOWCASE_VERSIONS = ("3.15.8", "5.12.2", "10.11.0")


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="decode an embedded example session (no robot needed)")
    p.add_argument("--session", type=Path, help="a session file of your own (same format)")
    p.set_defaults(run=run)


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


def run(args: argparse.Namespace) -> int:
    from .main import catalogue_for

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
    print("\nNext: rtde-spec fields --controller 5.12.2, rtde-spec decode HEX --from controller")
    return 0
