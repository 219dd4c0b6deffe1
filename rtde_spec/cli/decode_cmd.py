"""rtde-spec decode HEX_OR_FILE: packages to a table, JSON, JSON Lines, CSV or Parquet, streaming.

Files and stdin are read in pieces as they come (stdin as soon as bytes arrive), so
memory follows what has arrived, never what a size field claims. On standard output every
package decoded before a fault is written before the error; a file (-o) is put in place only
whole, so a fault leaves a file already there as it was. --lenient skips and counts what
does not decode instead (stderr says what, and where) and exits 0.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from functools import partial
from typing import TYPE_CHECKING, Any, cast

from rtde_spec._generated.constants import (
    PRIMARY_PORTS,
    RTDE_DIRECTIONS,
    RTDE_PORT,
    RTDE_PROTOCOLS,
    RTDE_SENDERS,
)
from rtde_spec.cli.arguments import RECIPE_FILE_HELP, existing_file, primary_version, recipe_file
from rtde_spec.cli.conventions import describe, output_file
from rtde_spec.cli.hex_dumps import looks_like_hex_forms
from rtde_spec.cli.inputs import from_hex_text, read_input, refuse_special, reject_capture, reject_recording
from rtde_spec.cli.options import add_lenient
from rtde_spec.cli.report import close_output, report_skipped
from rtde_spec.errors import DecodeError, RtdeSpecError, UsageError

if TYPE_CHECKING:
    from rtde_spec.output.base import Writer
    from rtde_spec.recipes.codec import RecipeCodec
    from rtde_spec.rtde.stream import Batch, Package

CHUNK = 8 << 20
HEAD = 4096  # bytes of stdin looked at to tell hex text from binary
FORMAT_CHOICES = ("table", "jsonl", "json", "csv", "parquet", "mcap")


def add_parser(sub: argparse._SubParsersAction) -> None:
    ports = "/".join(str(p) for p in PRIMARY_PORTS.values())
    p = sub.add_parser(
        "decode",
        help="decode RTDE or primary/secondary messages from hex or a file",
        **describe(
            "Decodes RTDE or primary/secondary packages from hex (plain, a dump of Wireshark, tshark -x, "
            "xxd, hexdump -C, 0x00,0x05, \\x00\\x05), a file of bytes or hex, or standard input, into a "
            "table, JSON (--json: one array), JSON Lines (--jsonl), CSV, Parquet or MCAP (-o FILE, the "
            "format from its suffix). Streamed: any size in constant memory; a fault stops at its offset, "
            "after every package before it; -o FILE is put in place only whole (one there stays as it was).",
            "rtde-spec decode 00045601 --from controller",
            "rtde-spec decode copied-from-wireshark.txt --from client --jsonl",
            "rtde-spec decode data.bin --recipe outputs.txt -o data.parquet",
            "rtde-spec decode --protocol primary capture_30001.bin --json",
        ),
    )
    p.add_argument(
        "data", metavar="HEX_OR_FILE", help="hex string, file (binary or hex text), or - for stdin"
    )
    p.add_argument(
        "--protocol",
        choices=("rtde", "primary"),
        default="rtde",
        help=f"rtde (port {RTDE_PORT}) or primary (ports {ports}) (default: rtde)",
    )
    p.add_argument(
        "--controller",
        type=primary_version,
        metavar="VERSION",
        help="primary: the controller version when the input has no Version message (a dump of one "
        "message, a stream joined late), e.g. 1.8 for a CB2; one in the input wins (default: the "
        "newest layouts)",
    )
    p.add_argument(
        "--protocol-version",
        type=int,
        choices=RTDE_PROTOCOLS,
        default=None,
        help="RTDE protocol version of the first package (default: 1 when the input starts with the "
        f"version request, else {max(RTDE_PROTOCOLS)}; a version exchange in the input switches it)",
    )
    p.add_argument(
        "--from",
        dest="sender",
        choices=RTDE_SENDERS,
        default="controller",
        help="who sent the bytes (default: controller)",
    )
    _add_output_options(p)
    add_lenient(
        p,
        "ignore bytes after the last field (and after a recipe's payload); skip and count "
        "packages that do not decode, say so on stderr and exit 0 (default: strict, stop at the first)",
    )
    p.add_argument(
        "--recipe",
        metavar="NAMES_OR_FILE",
        help="decode data packages with this recipe: a comma list or a recipe file (default: none)",
    )
    p.add_argument(
        "--recipe-key",
        metavar="KEY",
        help="which recipe of a --recipe file with several (default: the only one, else the only one "
        "of the sender's direction: outputs from the controller, inputs from a client)",
    )
    p.add_argument(
        "--no-progress", action="store_true", help="no progress bar (default: shown on a terminal)"
    )
    p.set_defaults(run=run)


def _add_output_options(p: argparse.ArgumentParser) -> None:
    """Where the packages go and as what: a table, JSON, JSON Lines, CSV, Parquet or MCAP."""
    p.add_argument(
        "--format",
        choices=FORMAT_CHOICES,
        help="output format; json is always one array of objects, one per package, whatever their "
        "number (jsonl: one object per line) (default: from the -o suffix, else table)",
    )
    p.add_argument(
        "-o", "--output", metavar="FILE", help="write to FILE instead of stdout (default, or -: stdout)"
    )
    p.add_argument(
        "--json", action="store_true", help="the same as --format json: a JSON array (default: off)"
    )
    p.add_argument(
        "--jsonl", action="store_const", const="jsonl", dest="format",
        help="the same as --format jsonl: one JSON object per line, streamed (default: off)",
    )  # fmt: skip


def recipe_codec(args: argparse.Namespace) -> RecipeCodec | None:
    if not args.recipe:
        return None
    from rtde_spec.cli.arguments import catalogue_for
    from rtde_spec.recipes.codec import RecipeCodec
    from rtde_spec.recipes.files import load_recipes, pick_recipe
    from rtde_spec.recipes.model import Direction, Recipe

    direction = cast(Direction, RTDE_DIRECTIONS[args.sender])
    cat = catalogue_for(args)
    # a pipe or device named as the recipe is neither a file to read nor a list of field names
    refuse_special(
        args.recipe, "a recipe file", f"give {RECIPE_FILE_HELP}, or field names as a comma list", "--recipe"
    )
    path = recipe_file(args.recipe)
    if path is not None:
        inputs, outputs = set(cat.names("input")), set(cat.names("output"))
        recipes = load_recipes(path)
        recipe = pick_recipe(recipes, args.recipe_key, direction, inputs, outputs, where=args.recipe)
    else:
        recipe = Recipe.parse(args.recipe)
    return RecipeCodec.for_names(recipe.names, direction, cat)


def chunks(args: argparse.Namespace) -> Iterator[bytes]:
    """The input in pieces: a binary file or stdin is streamed, a file with a progress bar on a terminal."""
    if args.data == "-":
        yield from stdin_chunks()
        return
    path = existing_file(args.data)
    if path is None:
        yield read_input(args.data)
        return
    with open(path, "rb") as f:
        head = f.read(CHUNK)
        reject_capture(head, args.data)
        reject_recording(head, args.data)
        if _is_hex_text(head):
            yield read_input(args.data)
            return
        bar = _progress(path.stat().st_size, args)
        while head:
            yield head
            if bar is not None:
                bar.update(len(head))
            head = f.read(CHUNK)
        if bar is not None:
            bar.close()


def stdin_chunks() -> Iterator[bytes]:
    """Binary stdin in the pieces it arrives in (no waiting for its end); hex text whole."""
    stream = sys.stdin.buffer
    if stream.isatty():  # a user may paste hex; one who meant a pipe sees why nothing happens
        print("rtde-spec decode: reading packages from the terminal (hex; end with Ctrl-D)", file=sys.stderr)
    read1: Callable[[int], bytes] = getattr(stream, "read1", stream.read)  # what has arrived, up to n
    head, ended = b"", False
    while len(head) < HEAD:
        piece = read1(HEAD - len(head))
        if not piece:
            ended = True  # not read again: a terminal's end (Ctrl-D) is given once, not for ever
            break
        head += piece
    reject_capture(head, "-")
    if _is_hex_text(head):
        yield from_hex_text(head if ended else head + stream.read())
        return
    if head:
        yield head
    while not ended and (piece := read1(CHUNK)):
        yield piece


def input_left(args: argparse.Namespace, offset: int | None) -> str:
    """How much input from `offset` on there is: known for a file, not for stdin or hex."""
    path = existing_file(args.data)
    if path is None or offset is None:
        return "the rest of the input"
    return f"{max(path.stat().st_size - offset, 0)} bytes"


def _is_hex_text(head: bytes) -> bool:
    plain = all(c in b"0123456789abcdefABCDEF \t\r\n:x" for c in head[:4096])
    return bool(head) and (plain or looks_like_hex_forms(head))


def _progress(total: int, args: argparse.Namespace) -> Any:
    if args.no_progress or not sys.stderr.isatty() or total < CHUNK:
        return None
    try:
        from tqdm import tqdm
    except ImportError:
        return None
    return tqdm(total=total, unit="B", unit_scale=True, desc="decode", file=sys.stderr, leave=False)


def run(args: argparse.Namespace) -> int:
    from rtde_spec.output.writers import format_for, open_writer

    if args.output == "-":  # the usual spelling of standard output, the default
        args.output = None
    if args.output:
        output_file(args.output)
    fmt = "json" if args.json and not args.format else format_for(args.output, args.format)
    if args.controller is not None and args.protocol != "primary":
        raise UsageError(
            "picks the primary interface's layouts; RTDE packages have one layout per recipe, not per "
            "version: add --protocol primary, or leave it out",
            subject="--controller",
        )
    if args.protocol == "primary":
        from rtde_spec.cli.primary_output import run_primary

        return run_primary(
            chunks(args),
            fmt,
            args.output,
            lenient=args.lenient,
            left=partial(input_left, args),
            version=args.controller,
        )
    codec = recipe_codec(args)
    writer = open_writer(fmt, args.output, background=True)
    try:
        total = decode_into(writer, args, codec, fmt)
    except BaseException as exc:
        close_output(writer, exc, "package")
        raise
    close_output(writer, None, "package")
    if total == 0:
        raise RtdeSpecError("no packages in the input")
    return 0


def decode_into(writer: Writer, args: argparse.Namespace, codec: RecipeCodec | None, fmt: str) -> int:
    """Stream every package into the writer; return how many there were."""
    from rtde_spec.rtde.stream import Package, StreamDecoder

    decoder = StreamDecoder(
        args.sender,
        protocol_version=args.protocol_version,
        codec=codec,
        strict=not args.lenient,
        batch=fmt != "table",
        skip_errors=args.lenient,
    )
    skipped: dict[str, int] = {}
    tabular = fmt in ("csv", "parquet") and codec is not None

    def emit(item: Package | Batch) -> None:
        if isinstance(item, Package):
            if tabular and item.values is None:
                skipped[item.message.NAME] = skipped.get(item.message.NAME, 0) + 1
                return
            writer.write(_record(item, codec, fmt, tabular))
            return
        columns = {name: item.array[name] for name in codec.names} if codec else {}
        if not tabular:
            import numpy as np

            size = len(item.array)
            offsets = item.offset + np.arange(size, dtype=np.int64) * item.array.dtype.itemsize
            columns = {"offset": offsets, "recipe_id": item.array["recipe_id"], **columns}
        writer.write_columns(columns)

    fault: DecodeError | None = None
    try:
        for chunk in chunks(args):
            for item in decoder.feed(chunk):
                emit(item)
        decoder.close()
    except DecodeError as exc:
        if not args.lenient:
            raise
        fault = exc  # cannot be framed, or ends inside a package: the rest is not decodable
    finally:
        if skipped:
            kinds = ", ".join(f"{n} x{c}" for n, c in skipped.items())
            print(f"note: not in the {fmt} table of data packages: {kinds}", file=sys.stderr)
    report_skipped(decoder.skipped, fault, input_left(args, fault.offset if fault else None), "package")
    return decoder.packages


def _record(item: Package, codec: RecipeCodec | None, fmt: str, tabular: bool) -> dict[str, object]:
    message = item.message
    fields = message.fields()
    if item.values is not None:
        fields.pop("payload")
        if tabular:
            return dict(item.values)
        fields.update(item.values)
    if fmt == "table":
        from rtde_spec.output.describe import describe

        infos = {i.name: i.info for i in codec.items if i.info is not None} if codec else {}
        described = {}
        for name, value in fields.items():
            info = infos.get(name)
            enum = message.ENUMS.get(name) or (info.enum if info else None)
            described[name] = describe(value, enum, info.bits if info else None)
        title = f"{message.PACKAGE_NAME} ({chr(message.PACKAGE_TYPE)!r})  {message.NAME}"
        return {"offset": item.offset, "package": title, **described}
    return {
        "offset": item.offset,
        "package": message.NAME,
        "package_type": chr(message.PACKAGE_TYPE),
        **fields,
    }
