"""rtde-spec record: a controller's outputs to CSV or Parquet, as UR's recorder names the columns."""

from __future__ import annotations

import argparse
import sys

from rtde_spec._generated.constants import RTDE_PORT
from rtde_spec.cli.common import existing_file
from rtde_spec.errors import UsageError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "record",
        help="record outputs from a controller (or the emulator) to CSV/Parquet/JSON Lines",
        description="Columns are named as UR's recorder names them (vectors as name_0..name_5). "
        "Ctrl-C or a dropped connection keeps every row received.",
    )
    p.add_argument("--host", required=True, help="controller address (required)")
    p.add_argument("--port", type=int, default=RTDE_PORT, help=f"RTDE port (default: {RTDE_PORT})")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--recipe", metavar="FILE", help="recipe file, any format (required: this or --fields)")
    what.add_argument(
        "--fields", metavar="A,B,...", help="output names, comma-separated (required: this or --recipe)"
    )
    p.add_argument("--frequency", type=float, default=125.0, help="output rate in Hz (default: 125)")
    stop = p.add_mutually_exclusive_group()
    stop.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: Ctrl-C)")
    stop.add_argument("--samples", type=int, metavar="N", help="stop after N rows (default: Ctrl-C)")
    p.add_argument(
        "-o", "--output", required=True, metavar="FILE", help="out.csv, out.parquet or out.jsonl (required)"
    )
    p.add_argument("--format", choices=("csv", "parquet", "jsonl"), help="default: from the -o suffix")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for replies (default: 5)")
    p.set_defaults(run=run)


def names_of(args: argparse.Namespace) -> list[str]:
    if args.fields:
        return [n.strip() for n in args.fields.split(",") if n.strip()]
    from rtde_spec.recipes.files import load_recipes

    path = existing_file(args.recipe)
    if path is None:
        raise UsageError("recipe file not found", subject=f"file {args.recipe}")
    outputs = [r for r in load_recipes(path) if r.direction in (None, "output")]
    if len(outputs) != 1:
        raise UsageError("needs exactly one output recipe", subject=f"file {args.recipe}")
    return list(outputs[0].names)


def run(args: argparse.Namespace) -> int:
    from rtde_spec.output.writers import format_for, open_writer
    from rtde_spec.rtde.client import RtdeClient
    from rtde_spec.rtde.recorder import BATCH_SECONDS, record

    fmt = format_for(args.output, args.format)
    if fmt not in ("csv", "parquet", "jsonl"):
        raise UsageError(f"-o {args.output}: use .csv, .parquet or .jsonl (or --format)")
    names = names_of(args)
    bar = _progress(args)
    # the reader wakes every ~0.1 s, half the recorder's write interval: no row waits longer
    batch = max(1, int(args.frequency * BATCH_SECONDS / 2))
    with RtdeClient(args.host, args.port, timeout=args.timeout, batch=batch) as client:
        writer = open_writer(fmt, args.output)
        try:
            result = record(
                client,
                names,
                args.frequency,
                writer,
                duration=args.duration,
                samples=args.samples,
                progress=bar.update if bar is not None else None,
            )
        finally:
            writer.close()
            if bar is not None:
                bar.close()
    print(
        f"recorded {result.rows} rows of {len(names)} fields in {result.seconds:.1f} s to {args.output} "
        f"(controller {client.controller_version}, skipped {result.skipped}, stopped by {result.stopped_by})",
        file=sys.stderr,
    )
    return 1 if result.stopped_by == "connection" else 0


def _progress(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    if not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    total = args.samples or (int(args.duration * args.frequency) if args.duration else None)
    return tqdm(total=total, unit="rows", desc="record", file=sys.stderr)
