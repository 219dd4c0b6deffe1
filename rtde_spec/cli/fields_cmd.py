"""rtde-spec fields: the field catalogue, optionally for one controller version."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from rtde_spec.cli.common import catalogue_for, controller_version
from rtde_spec.output.text import print_json, table

if TYPE_CHECKING:
    from rtde_spec.spec.catalogue import Catalogue, FieldInfo


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fields", help="list RTDE fields (register families expanded)")
    p.add_argument(
        "--controller",
        metavar="VERSION",
        type=controller_version,
        help="only fields available on this controller version (default: every field)",
    )
    p.add_argument("--direction", choices=("input", "output"), help="only this direction (default: both)")
    p.add_argument("--json", action="store_true", help="print JSON (default: a table)")
    p.set_defaults(run=run)


def field_record(info: FieldInfo, catalogue: Catalogue) -> dict[str, object]:
    return {
        "name": info.name,
        "type": info.type,
        "direction": info.direction,
        "size": info.size,
        "since": {line: str(v) for line, v in info.since.items()},
        "unit": info.unit,
        "enum": info.enum,
        "bits": info.bits,
        "family": info.family,
        "index": info.index,
        "reserved": info.reserved,
        "deprecated": info.deprecated,
        "sources": list(info.sources),
        "doc": info.doc,
    }


def run(args: argparse.Namespace) -> int:
    catalogue = catalogue_for(args)
    infos = catalogue.fields(args.direction, args.controller)
    if args.json:
        print_json([field_record(i, catalogue) for i in infos])
        return 0
    rows = [
        [i.name, i.direction, i.type, i.size, catalogue.since_text(i), i.unit or "", i.doc or ""]
        for i in infos
    ]
    print(table(["name", "direction", "type", "bytes", "since", "unit", "doc"], rows))
    where = f" on {args.controller}" if args.controller else ""
    print(f"\n{len(infos)} fields{where}")
    return 0
