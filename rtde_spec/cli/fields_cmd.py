"""rtde-spec fields: the field catalogue, optionally for one controller version."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from rtde_spec.cli.arguments import catalogue_for, release_version
from rtde_spec.cli.conventions import describe
from rtde_spec.cli.options import add_controller
from rtde_spec.output.text import print_json, table

if TYPE_CHECKING:
    from rtde_spec.metamodel.catalogue import Catalogue, FieldInfo


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "fields",
        help="list RTDE fields (register families expanded)",
        **describe(
            "Lists the RTDE fields the spec knows, register families expanded, with type, unit, direction "
            "and the version each product line has had them since; --controller keeps those a version "
            "offers, --diff A B shows what a release added or removed, --json prints one JSON document.",
            "rtde-spec fields --controller 5.12.2 --direction output",
            "rtde-spec fields --diff 5.10 5.11",
            "rtde-spec fields --extra-fields my_fields.yaml --controller 5.25.0 --json",
        ),
    )
    add_controller(p, "only fields available on this controller version (default: every field)")
    p.add_argument("--direction", choices=("input", "output"), help="only this direction (default: both)")
    p.add_argument("--json", action="store_true", help="print JSON (default: a table)")
    p.add_argument(
        "--primary",
        action="store_true",
        help="list primary/secondary interface fields instead, with since (default: off)",
    )
    p.add_argument(
        "--diff",
        nargs=2,
        metavar=("A", "B"),
        type=release_version,
        help="fields added and removed from controller version A to B, per interface (default: off)",
    )
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
    if args.diff:
        from rtde_spec.cli.fields_diff import print_diff

        return print_diff(catalogue, args.diff[0], args.diff[1], args.json)
    if args.primary:
        return _run_primary(args, catalogue)
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


def _run_primary(args: argparse.Namespace, catalogue: Catalogue) -> int:
    from rtde_spec.metamodel.primary_fields import available, primary_fields

    infos = primary_fields(catalogue)
    if args.controller:
        infos = [i for i in infos if available(i, catalogue, args.controller)]
    since = [", ".join(f"{k} {v}" for k, v in i.since.items()) or "not available" for i in infos]
    if args.json:
        print_json(
            [
                {
                    "message": i.message,
                    "name": i.name,
                    "type": i.type,
                    "since": {k: str(v) for k, v in i.since.items()},
                    "doc": i.doc,
                }
                for i in infos
            ]
        )
        return 0
    rows = [[i.message, i.name, i.type, s, i.doc or ""] for i, s in zip(infos, since, strict=True)]
    print(table(["message", "field", "type", "since", "doc"], rows))
    where = f" on {args.controller}" if args.controller else ""
    print(f"\n{len(infos)} primary fields{where}")
    return 0
