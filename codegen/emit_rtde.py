"""Emit the RTDE package layer: construct structs and pydantic models, one per message.

A message is one layout of one package type for a set of protocol versions and
senders (e.g. the text message of protocol 1 differs by sender).
"""

from __future__ import annotations

import re

from rtde_spec.metamodel.schema import MessageSpec, Primitive, Spec

from .emit_construct import CONSTRUCT_BY_STRUCT, prims_of, struct_body
from .model_fields import field_lines
from .render import PY_HEADER, camel, docstring, upper

CONSTRUCT_NAMES = (
    "Array",
    "GreedyBytes",
    "GreedyRange",
    "GreedyString",
    "If",
    "PascalString",
    "Prefixed",
    "Switch",
)


def emit_rtde_structs(spec: Spec) -> str:
    prims = prims_of(spec)
    pk = spec.packages
    out = [
        PY_HEADER,
        '"""construct structs of every RTDE package body, plus whole-package structs.\n\n'
        "`<NAME>` parses the body (after the header); `<NAME>_PACKAGE` a whole package.\n"
        '"""\n\n',
        "from construct import (\n",
    ]
    used = {"Struct"}
    bodies: list[str] = []
    for msg in pk.messages:
        parts = [struct_body([fld], prims, "    ", "ascii") for fld in msg.fields]
        for part in parts:
            used.update(n for n in CONSTRUCT_BY_STRUCT.values() if n in part)
            used.update(n for n in CONSTRUCT_NAMES if re.search(rf"\b{n}\b", part))
        body = f"\n{upper(msg.name)} = Struct(\n{''.join(parts)})\n"
        body += docstring(msg.doc or msg.name, indent="")
        bodies.append(body)
    header = [f'    "{h.name}" / {CONSTRUCT_BY_STRUCT[prims[h.type].struct]},\n' for h in pk.header]
    used.update(CONSTRUCT_BY_STRUCT[prims[h.type].struct] for h in pk.header)
    out += [f"    {name},\n" for name in sorted(used)]
    out.append(")\n\nfrom rtde_spec.wire.construct_ext import csv_string, package_struct\n")
    out.append(f"\nHEADER = Struct(\n{''.join(header)})\n")
    out.append('"""Header of every package: size counts the whole package."""\n')
    out += bodies
    size_c = CONSTRUCT_BY_STRUCT[prims[pk.header[0].type].struct]
    type_c = CONSTRUCT_BY_STRUCT[prims[pk.header[1].type].struct]
    out.append("\n")
    for msg in pk.messages:
        out.append(
            f"{upper(msg.name)}_PACKAGE = package_struct("
            f"{size_c}, {type_c}, {ord(msg.type)}, {upper(msg.name)})\n"
        )
    return "".join(out)


def header_format(spec: Spec) -> str:
    """struct format of the RTDE header, from the spec's header fields."""
    prims = prims_of(spec)
    return order_of(spec.packages.byte_order) + "".join(prims[h.type].struct for h in spec.packages.header)


def order_of(byte_order: str) -> str:
    """struct's prefix for a spec's byte order."""
    return {"big": ">", "little": "<"}[byte_order]


def _model_doc(msg: MessageSpec, spec: Spec) -> str:
    names = {p.code: p.name for p in spec.packages.package_types}
    senders = " and ".join(msg.senders)
    protos = ", ".join(map(str, msg.protocols))
    text = msg.doc or ""
    return f"{text}\n\n{names[msg.type]} ({msg.type!r}) from {senders}; protocol {protos}."


def _model(msg: MessageSpec, spec: Spec, prims: dict[str, Primitive]) -> str:
    names = {p.code: p.name for p in spec.packages.package_types}
    out = [f"\n\nclass {camel(msg.name)}(RtdeMessage):\n", docstring(_model_doc(msg, spec)), "\n"]
    out.append(f"    NAME: ClassVar[str] = {msg.name!r}\n")
    out.append(f"    PACKAGE_TYPE: ClassVar[int] = {ord(msg.type)}  # {msg.type!r}\n")
    out.append(f"    PACKAGE_NAME: ClassVar[str] = {names[msg.type]!r}\n")
    out.append(f"    SENDERS: ClassVar[tuple[str, ...]] = {tuple(msg.senders)!r}\n")
    out.append(f"    PROTOCOLS: ClassVar[tuple[int, ...]] = {tuple(msg.protocols)!r}\n")
    structs = "rtde_spec._generated.rtde_structs"
    out.append(f'    STRUCT: ClassVar["Construct"] = struct_of({structs!r}, {upper(msg.name)!r})\n')
    out.append(f"    HEADER_FORMAT: ClassVar[str] = {header_format(spec)!r}\n")
    out.append(f"    MAX_SIZE: ClassVar[int] = {spec.packages.limits.package_max_bytes}\n")
    enums = {f.name: f.enum for f in msg.fields if f.enum}
    out.append(f"    ENUMS: ClassVar[dict[str, str]] = {enums!r}\n")
    leading = []
    for fld in msg.fields:
        if fld.type not in prims or fld.length is not None:
            break
        leading.append(prims[fld.type].struct)
    fixed = order_of(spec.packages.byte_order) + "".join(leading)
    out.append(f"    FIXED_FORMAT: ClassVar[str] = {fixed!r}  # leading fixed fields\n")
    out.append(f"    FIELDS: ClassVar[tuple[str, ...]] = {tuple(f.name for f in msg.fields)!r}\n")
    if msg.fields:
        out.append("\n")
    out += field_lines(msg.fields, prims, optional=False, text="ascii")
    return "".join(out)


def emit_rtde_models(spec: Spec) -> str:
    prims = prims_of(spec)
    pk = spec.packages
    out = [
        PY_HEADER,
        '"""pydantic models of every RTDE package layout, and the codec\'s lookup tables."""\n\n',
        "from typing import TYPE_CHECKING, Annotated, ClassVar\n\n",
        "from pydantic import Field\n\n",
        "from rtde_spec._generated.constants import RTDE_PACKAGE_TYPES\n",
        "from rtde_spec.wire.rtde_messages import RtdeMessage, struct_of\n",
        "{model_types_import}",
        f"PORT = {pk.port}\n",
        f"HEADER_FORMAT = {header_format(spec)!r}\n",
        '"""struct format of the header (size, type)."""\n',
        f"HEADER_SIZE = {sum(prims[h.type].size for h in pk.header)}\n",
        f"HEADER_FIELDS: tuple[str, ...] = {tuple(h.name for h in pk.header)!r}\n",
        f"LIMITS: dict[str, int] = {pk.limits.model_dump()!r}\n",
        "PACKAGE_TYPES = RTDE_PACKAGE_TYPES  # type code -> the document's name of the type\n",
    ]
    out.append(f"SENDERS: tuple[str, ...] = {tuple(pk.senders)!r}\n")
    protocols = sorted({p for m in pk.messages for p in m.protocols})
    out.append(f"PROTOCOLS: tuple[int, ...] = {tuple(protocols)!r}\n")
    models = [_model(msg, spec, prims) for msg in pk.messages]
    used = [n for n in ("AsciiStr", "CsvItem", "ShortAsciiStr") if any(n in m for m in models)]
    imports = f"from rtde_spec.wire.model_types import {', '.join(used)}\n" if used else ""
    imports += "\nif TYPE_CHECKING:  # construct loads with the first STRUCT read\n"
    imports += "    from construct import Construct\n\n"
    out = [part.replace("{model_types_import}", imports) for part in out]
    out += models
    out.append("\n\nMESSAGES: tuple[type[RtdeMessage], ...] = (\n")
    out += [f"    {camel(m.name)},\n" for m in pk.messages]
    out.append(")\n\nBY_KEY: dict[tuple[int, str, int], type[RtdeMessage]] = {\n")
    for msg in pk.messages:
        for sender in msg.senders:
            for proto in msg.protocols:
                out.append(f"    ({ord(msg.type)}, {sender!r}, {proto}): {camel(msg.name)},\n")
    out.append("}\n")
    return "".join(out)
