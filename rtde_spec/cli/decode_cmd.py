"""rtde-spec decode HEX_OR_FILE: one or more concatenated packages as a table or JSON."""

from __future__ import annotations

import argparse

from .._generated import rtde_models as gen
from ..codec import decode_stream
from ..describe import describe
from ..message_base import RtdeMessage
from .render import print_json, read_input, table


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("decode", help="decode RTDE packages from hex or a file")
    p.add_argument("data", metavar="HEX_OR_FILE", help="hex string, file (binary or hex), or -")
    p.add_argument("--protocol-version", type=int, choices=gen.PROTOCOLS, default=2)
    p.add_argument(
        "--from",
        dest="sender",
        choices=gen.SENDERS,
        default="controller",
        help="who sent the bytes (default: controller)",
    )
    p.add_argument("--json", action="store_true", help="JSON keyed by the spec's field names")
    p.add_argument("--lenient", action="store_true", help="ignore bytes after the last field")
    p.set_defaults(run=run)


def package_record(offset: int, message: RtdeMessage) -> dict[str, object]:
    """JSON shape of one package: where, what, then the fields by spec name."""
    record: dict[str, object] = {
        "offset": offset,
        "package": message.NAME,
        "package_type": chr(message.PACKAGE_TYPE),
    }
    record.update(message.fields())
    return record


def print_packages(packages: list[tuple[int, RtdeMessage]]) -> None:
    for offset, message in packages:
        title = f"@{offset}  {message.PACKAGE_NAME} ({chr(message.PACKAGE_TYPE)!r})  {message.NAME}"
        rows = [
            [name, describe(value, message.ENUMS.get(name))]
            for name, value in message.fields().items()
        ]
        print(title)
        if rows:
            print(table(["field", "value"], rows, max_width=100))
        print()


def run(args: argparse.Namespace) -> int:
    data = read_input(args.data)
    packages = list(
        decode_stream(
            data,
            protocol_version=args.protocol_version,
            sender=args.sender,
            strict=not args.lenient,
        )
    )
    if args.json:
        records = [package_record(o, m) for o, m in packages]
        print_json(records[0] if len(records) == 1 else records)
    else:
        print_packages(packages)
    return 0
