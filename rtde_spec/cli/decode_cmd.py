"""rtde-spec decode HEX_OR_FILE: one or more concatenated packages as a table or JSON."""

from __future__ import annotations

import argparse
from pathlib import Path

from rtde_spec._generated import rtde_models as gen
from rtde_spec._generated.primary_models import PORTS as _PRIMARY
from rtde_spec.cli.render import print_json, read_input, table
from rtde_spec.errors import RecipeError
from rtde_spec.output.describe import describe
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.recipes.files import load_recipes
from rtde_spec.recipes.model import Recipe
from rtde_spec.rtde.codec import decode_stream
from rtde_spec.rtde.messages import RtdeMessage
from rtde_spec.spec.catalogue import Direction

PRIMARY_PORTS = "/".join(str(p) for p in _PRIMARY.values())


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("decode", help="decode RTDE or primary/secondary messages from hex or a file")
    p.add_argument("data", metavar="HEX_OR_FILE", help="hex string, file (binary or hex), or -")
    p.add_argument(
        "--protocol",
        choices=("rtde", "primary"),
        default="rtde",
        help=f"rtde (port {gen.PORT}, default) or primary (ports {PRIMARY_PORTS})",
    )
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
    p.add_argument(
        "--recipe",
        metavar="NAMES_OR_FILE",
        help="decode data packages with this recipe (comma list or recipe file)",
    )
    p.set_defaults(run=run)


def field_values(message: RtdeMessage, codec: RecipeCodec | None) -> dict[str, object]:
    """The package's fields; a data package's payload decoded when a recipe is given."""
    fields = message.fields()
    if codec is not None and isinstance(message, gen.DataPackage):
        fields.pop("payload")
        fields.update(codec.decode(message.payload))
    return fields


def package_record(offset: int, message: RtdeMessage, codec: RecipeCodec | None = None) -> dict[str, object]:
    """JSON shape of one package: where, what, then the fields by spec name."""
    record: dict[str, object] = {
        "offset": offset,
        "package": message.NAME,
        "package_type": chr(message.PACKAGE_TYPE),
    }
    record.update(field_values(message, codec))
    return record


def print_packages(packages: list[tuple[int, RtdeMessage]], codec: RecipeCodec | None = None) -> None:
    for offset, message in packages:
        title = f"@{offset}  {message.PACKAGE_NAME} ({chr(message.PACKAGE_TYPE)!r})  {message.NAME}"
        infos = {}
        if codec is not None:
            infos = {i.name: i.info for i in codec.items if i.info is not None}
        rows = []
        for name, value in field_values(message, codec).items():
            info = infos.get(name)
            enum = message.ENUMS.get(name) or (info.enum if info else None)
            rows.append([name, describe(value, enum, info.bits if info else None)])
        print(title)
        if rows:
            print(table(["field", "value"], rows, max_width=100))
        print()


def recipe_codec(args: argparse.Namespace) -> RecipeCodec | None:
    if not args.recipe:
        return None
    from rtde_spec.cli.main import catalogue_for

    direction: Direction = "output" if args.sender == "controller" else "input"
    if Path(args.recipe).exists():
        (recipe, *rest) = load_recipes(args.recipe)
        if rest:
            raise RecipeError("--recipe file holds several recipes; give one", field=args.recipe)
    else:
        recipe = Recipe.parse(args.recipe)
    return RecipeCodec.for_names(recipe.names, direction, catalogue_for(args))


def run(args: argparse.Namespace) -> int:
    if args.protocol == "primary":
        from rtde_spec.cli.primary_output import run_primary

        return run_primary(read_input(args.data), args.json)
    codec = recipe_codec(args)
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
        records = [package_record(o, m, codec) for o, m in packages]
        print_json(records[0] if len(records) == 1 else records)
    else:
        print_packages(packages, codec)
    return 0
