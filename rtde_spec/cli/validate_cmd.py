"""rtde-spec validate RECIPE...: check recipes offline against the spec.

Exit 0 when valid (warnings allowed), 1 when invalid, 2 on usage errors
(unreadable or malformed recipe files, unknown controller lines).
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from rtde_spec.cli.arguments import recipe_file
from rtde_spec.cli.conventions import describe, plural
from rtde_spec.cli.options import add_controller
from rtde_spec.cli.report import EXIT_USAGE
from rtde_spec.errors import RtdeSpecError
from rtde_spec.output.text import print_json, table
from rtde_spec.recipes.model import FILE_FORMATS, Recipe

if TYPE_CHECKING:
    from rtde_spec.recipes.validation import RecipeReport, ValidationReport


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "validate",
        help="validate recipes offline for a controller version",
        **describe(
            "Validates recipes offline, every problem at once: unknown names (with did-you-mean), direction, "
            "availability on a controller version, types that disagree with the spec, duplicates, the "
            "setup size limit, the frequency range, reserved registers. Exit codes: 0 valid (warnings "
            "allowed), 1 invalid, 2 usage error (missing or unreadable file, unknown version, bad option).",
            "rtde-spec validate timestamp,actual_q,safety_status --controller 5.4.0 --frequency 200",
            "rtde-spec validate rtde_config.xml --controller 5.12.2 --json",
            "rtde-spec validate recipe.txt --input-format lines --direction output",
        ),
    )
    p.add_argument(
        "recipes",
        nargs="+",
        metavar="RECIPE",
        help="a recipe file (XML, YAML, JSON, one name per line) or a comma list",
    )
    add_controller(
        p,
        "controller version, e.g. 3.15.8, 5.12.2, 10.11.0 (default: the version a recipe file "
        "names, else availability by version is not checked)",
    )
    p.add_argument(
        "--frequency", type=float, metavar="HZ", help="output frequency (default: the file's, else none)"
    )
    p.add_argument(
        "--direction",
        choices=("input", "output"),
        help="default: the file's, else inferred from the names",
    )
    p.add_argument(
        "--input-format", dest="format", choices=FILE_FORMATS, help="recipe file format (default: detect)"
    )
    p.add_argument("--format", choices=FILE_FORMATS, help=argparse.SUPPRESS)  # the old --input-format
    p.add_argument("--json", action="store_true", help="print the report as JSON (default: a table)")
    p.set_defaults(run=run)


def collect(args: argparse.Namespace) -> list[Recipe]:
    from rtde_spec.recipes.files import load_recipes

    recipes: list[Recipe] = []
    for arg in args.recipes:
        path = recipe_file(arg, "recipe")
        if path is not None:
            recipes += load_recipes(path, args.format)
        else:
            recipes.append(Recipe.parse(arg).with_(source="argument"))
    return recipes


def report_json(report: ValidationReport) -> dict[str, object]:
    def one(r: RecipeReport) -> dict[str, object]:
        return {
            "key": r.recipe.key,
            "source": r.recipe.source,
            "direction": r.direction,
            "valid": r.valid,
            "answer": r.answer,
            "payload_bytes": r.payload_bytes,
            "rate_divisor": r.rate_divisor,
            "effective_frequency": r.effective_frequency,
            "fields": [vars(row) for row in r.rows],
            "problems": [vars(p) for p in r.problems],
        }

    return {
        "valid": report.valid,
        "controller": report.controller,
        "line": report.line,
        "recipes": [one(r) for r in report.recipes],
        "problems": [vars(p) for p in report.problems],
    }


def print_report(report: ValidationReport) -> None:
    if report.controller:
        target = f"controller {report.controller} ({report.line})"
    elif any(r.recipe.controller for r in report.recipes):
        target = "the controller version each recipe names"
    else:
        target = "no controller version given: availability by version not checked"
    print(f"Validating {plural(len(report.recipes), 'recipe')} for {target}\n")
    for r in report.recipes:
        state = "valid" if r.valid else "INVALID"
        extra = f", every {r.rate_divisor} cycles = {r.effective_frequency:.4g} Hz" if r.rate_divisor else ""
        print(
            f"{r.label} ({r.direction}, {len(r.rows)} fields, "
            f"{r.payload_bytes} payload bytes{extra}): {state}"
        )
        rows = [[x.name, x.type or "?", x.size or "", x.since, x.status, x.message] for x in r.rows]
        if rows:
            print(
                table(
                    ["name", "type", "bytes", "available since", "status", "message"],
                    rows,
                    max_width=90,
                )
            )
        general = [p for p in r.problems if p.field is None]
        for p in general:
            print(f"  {p.severity}: {p.message} [{p.code}]")
        print()
    for p in report.problems:
        print(p)
    errors = sum(p.severity == "error" for p in report.all_problems)
    warnings = sum(p.severity == "warning" for p in report.all_problems)
    verdict = "valid" if report.valid else "invalid"
    print(f"{verdict}: {plural(errors, 'error')}, {plural(warnings, 'warning')}")


def run(args: argparse.Namespace) -> int:
    from rtde_spec.cli.arguments import catalogue_for
    from rtde_spec.recipes.validation import validate_recipes

    try:
        catalogue = catalogue_for(args)
        recipes = collect(args)
        if args.controller:
            catalogue.line_of(args.controller)
        report = validate_recipes(
            recipes,
            controller=args.controller,
            frequency=args.frequency,
            direction=args.direction,
            catalogue=catalogue,
        )
    except RtdeSpecError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    if args.json:
        print_json(report_json(report))
    else:
        print_report(report)
    return 0 if report.valid else 1
