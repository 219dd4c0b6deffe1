"""The spec's plain constants (ports, protocol versions, senders) as a module with no imports.

The command line reads them for its help text without loading pydantic or construct.
"""

from __future__ import annotations

from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.schema import Spec

from .emit_rtde import order_of
from .render import PY_HEADER


def emit_constants(spec: Spec) -> str:
    pk = spec.packages
    protocols = tuple(sorted({p for m in pk.messages for p in m.protocols}))
    prims = {p.name: p for p in spec.primitives.primitives}
    header = order_of(pk.byte_order) + "".join(prims[h.type].struct for h in pk.header)
    data = next(m for m in pk.messages if m.name == "data_package")
    fixed = [f for f in data.fields if f.type in prims and f.length is None]
    prefix_codes = "".join(prims[f.type].struct for f in fixed)
    prefix_names = (*(h.name for h in pk.header), *(f.name for f in fixed))
    sizes = [prims[h.type].size for h in pk.header] + [prims[f.type].size for f in fixed]
    prefix_offsets = tuple(sum(sizes[:i]) for i in range(len(sizes)))
    lines = [
        PY_HEADER,
        '"""Plain constants of the spec, importable without pydantic or construct."""\n\n',
        f"RTDE_PORT = {pk.port}\n",
        f"RTDE_PROTOCOLS: tuple[int, ...] = {protocols!r}\n",
        f"RTDE_SENDERS: tuple[str, ...] = {tuple(pk.senders)!r}\n",
        f"PRIMARY_PORTS: dict[str, int] = {dict(spec.primary.ports)!r}\n",
        f"RTDE_HEADER_FORMAT = {header!r}\n",
        f"RTDE_HEADER_FIELDS: tuple[str, ...] = {tuple(h.name for h in pk.header)!r}\n",
        f"RTDE_LIMITS: dict[str, int] = {pk.limits.model_dump()!r}\n",
        f"RTDE_ANSWERS: dict[str, str] = {pk.answers.model_dump()!r}\n",
        '"""Words a setup reply puts in its type list instead of a type."""\n',
        f"RTDE_DIRECTIONS: dict[str, str] = {dict(pk.directions)!r}\n",
        '"""Sender -> the direction of the recipes its data packages carry."""\n',
        f"BYTE_ORDER = {order_of(pk.byte_order)!r}\n",
        '"""struct prefix of the byte order every RTDE field is sent in."""\n',
        f"PRIMARY_BYTE_ORDER = {order_of(spec.primary.byte_order)!r}\n",
        '"""struct prefix of the byte order of the primary/secondary interfaces."""\n',
        f"DATA_PACKAGE_TYPE = {ord(data.type)}  # {data.type!r}\n",
        f"DATA_PACKAGE_PREFIX_FORMAT = {header + prefix_codes!r}\n",
        '"""struct format of a data package up to its payload: the header, then the recipe id."""\n',
        f"DATA_PACKAGE_PREFIX_FIELDS: tuple[str, ...] = {prefix_names!r}\n",
        f"DATA_PACKAGE_PREFIX_OFFSETS: tuple[int, ...] = {prefix_offsets!r}\n",
        '"""Byte offset of each prefix field (size, type, recipe id) in a data package."""\n',
        "DATA_WITHOUT_RECIPE_ID: dict[tuple[str, int], int] = {\n",
        *(
            f"    ({sender!r}, {proto}): {rule.implied!r},\n"
            for rule in pk.data_recipe_id
            if rule.implied is not None
            for sender in rule.senders
            for proto in rule.protocols
        ),
        "}\n",
        '"""(sender, protocol) -> the recipe id of a data package sent without its id byte (spec:\n'
        "packages.yaml data_recipe_id). Pairs not listed always carry the id. A decoder tells\n"
        "the forms apart by the package size: the recipe's payload plus the prefix, with or\n"
        'without the id."""\n',
        "DATA_SENT_WITHOUT_RECIPE_ID: frozenset[tuple[str, int]] = frozenset({\n",
        *(
            f"    ({sender!r}, {proto}),\n"
            for rule in pk.data_recipe_id
            if rule.sent == "without"
            for sender in rule.senders
            for proto in rule.protocols
        ),
        "})\n",
        '"""(sender, protocol) pairs whose data packages a real sender sends without the id byte\n'
        '(spec: packages.yaml data_recipe_id `sent`): the form the emulator writes for them."""\n',
        "RTDE_PACKAGE_TYPES: dict[int, str] = {\n",
        *(f"    {ord(p.code)}: {p.name!r},  # {p.code!r}\n" for p in pk.package_types),
        "}\n",
        '"""Package type code -> the name the protocol document gives the type."""\n',
        "RTDE_PACKAGES: dict[tuple[int, str, int], str] = {\n",
        *(
            f"    ({ord(m.type)}, {sender!r}, {proto}): {m.name!r},\n"
            for m in pk.messages
            for sender in m.senders
            for proto in m.protocols
        ),
        "}\n",
        '"""(type code, sender, protocol version) -> the spec name of its layout."""\n',
        "PRODUCT_LINES: dict[str, tuple[int, ...]] = {\n",
    ]
    for line in spec.product_lines.product_lines:
        lines.append(f"    {line.id!r}: {tuple(line.majors)!r},\n")
    lines.append("}\n")
    return "".join(lines)


def emit_catalogue_data(catalogue: Catalogue) -> str:
    """The field catalogue as plain tuples, so the runtime builds it without pydantic or YAML."""
    rows = catalogue.table_rows()
    out = [
        PY_HEADER,
        '"""The field catalogue as plain rows (see rtde_spec.metamodel.catalogue.Catalogue.builtin)."""\n\n',
        "from typing import Any\n\n",
        "# (id, name, majors, first_version, inherits, rtde_max_frequency, setup_names_max_bytes)\n",
        "LINES: tuple[tuple[Any, ...], ...] = (\n",
        *(f"    {row!r},\n" for row in rows["LINES"]),
        ")\n\n# (name, size, count, element, struct, kind, bounds)\n",
        "WIRE_TYPES: tuple[tuple[Any, ...], ...] = (\n",
        *(f"    {row!r},\n" for row in rows["WIRE_TYPES"]),
        ")\n\n# (name, direction, type, doc, unit, enum, bits, deprecated, reserved, sources, family,\n",
        "#  index, since per product line)\n",
        "FIELDS: tuple[tuple[Any, ...], ...] = (\n",
        *(f"    {row!r},\n" for row in rows["FIELDS"]),
        ")\n",
    ]
    return "".join(out)
