"""rtde-spec: decode packages, list fields, validate recipes, run the demo.

Errors print `error: ...` and exit non-zero; --debug shows the traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable
from types import ModuleType

from rtde_spec.cli import decode_cmd, demo_cmd, fields_cmd, validate_cmd
from rtde_spec.errors import RtdeSpecError
from rtde_spec.spec.catalogue import Catalogue

COMMANDS: tuple[ModuleType, ...] = (demo_cmd, decode_cmd, fields_cmd, validate_cmd)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rtde-spec",
        description="Universal Robots RTDE spec, codec and tools.",
    )
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    parser.add_argument(
        "--extra-fields",
        action="append",
        default=[],
        metavar="YAML",
        help="add fields from a YAML file shaped like spec/rtde/fields.yaml (repeatable)",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for module in COMMANDS:
        module.add_parser(sub)
    return parser


def catalogue_for(args: argparse.Namespace) -> Catalogue:
    """The built-in catalogue plus $RTDE_SPEC_EXTRA_FIELDS and --extra-fields files."""
    base = Catalogue.default()
    return base.with_extra(*args.extra_fields) if args.extra_fields else base


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    run: Callable[[argparse.Namespace], int] = args.run
    try:
        return run(args)
    except BrokenPipeError:
        # the reader (e.g. `head`) closed the pipe: not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except RtdeSpecError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except (OSError, ValueError) as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
