"""The primary interface as UR's docs site and client-interface pages list it: C-like rows.

    Joint data
    int packageSize
    unsigned char packageType = JOINT_DATA = 1
    for each joint:
    double q_actual
    ...
    end

A sub-package starts at `int packageSize`; its title is the line before. "for each joint:"
opens a group repeated 6 times, closed by "end"; "(if X is installed, also the following:"
opens a group present only when X is, closed by a line ending in ")". These pages have no
version column.
"""

from __future__ import annotations

import re

from rtde_spec.importers.model import DocLayoutField, DocMember
from rtde_spec.importers.primary_text import key

_C_TYPES = {
    "unsigned char": "uint8",
    "char": "int8",
    "bool": "bool",
    "short": "int16",
    "unsigned short": "uint16",
    "int": "int32",
    "unsigned int": "uint32",
    "long": "int64",
    "unsigned long": "uint64",
    "float": "float",
    "double": "double",
}
_TYPE = r"unsigned (?:char|short|int|long)|uint\d+_t|int\d+_t|char|bool|short|int|long|float|double"
ROW = re.compile(
    rf"^({_TYPE})(?:\s+([A-Za-z_][A-Za-z0-9_]*))?(?:\[(\d*)\])?(?:\s*=\s*([A-Z_][A-Z0-9_]*)\s*=\s*(\d+))?;?$"
)
_FOR_EACH = re.compile(r"^for each joint\s*:?$", re.I)
_IF = re.compile(r"^\(?if (\w+)(?: interface)? is installed.*following:?$", re.I)
#: whether a text is in this form: a package type given as NAME = number
SIGN = re.compile(r"packageType\s*=\s*[A-Z_]+\s*=\s*\d+")


def _prim(text: str) -> str:
    return _C_TYPES.get(text, text.removesuffix("_t"))


def read_listing(text: str) -> list[DocMember]:
    """Every sub-package listed in the C-like form, with its rows and groups."""
    lines = [(n, raw.strip()) for n, raw in enumerate(text.splitlines(), start=1) if raw.strip()]
    members: list[DocMember] = []
    member: DocMember | None = None
    family: int | None = None
    group = ""
    for i, (number, line) in enumerate(lines):
        m = ROW.match(line)
        if m is not None and m.group(2) and key(m.group(2)) == "packagesize":
            title = lines[i - 1][1] if i else "sub-package"
            member = DocMember(title, family or 16, None, lines[i - 1][0] if i else number)
            members.append(member)
            group = ""
            continue
        if m is not None and m.group(5) is not None:
            name = key(m.group(2) or "")
            if name == "messagetype":
                family = int(m.group(5))
            elif member is not None:
                member.member_type = int(m.group(5))
            continue
        if member is None:
            continue
        if _FOR_EACH.match(line):
            group = "repeat 6"
        elif line.lower() == "end":
            group = ""
        elif (w := _IF.match(line)) is not None:
            group = f"when {key(w.group(1))}installed"
        elif m is not None and m.group(2):
            type_ = _prim(m.group(1))
            if m.group(3) is not None:
                type_ = (
                    "string" if m.group(1) == "char" else f"{type_}[{m.group(3)}]" if m.group(3) else "bytes"
                )
            member.fields.append(DocLayoutField(m.group(2), key(m.group(2)), type_, "", number, group))
            if line.rstrip(";").endswith(")") or line.endswith(")"):
                group = ""
        elif line.endswith(")") and group.startswith("when"):
            group = ""
    return [m for m in members if m.member_type is not None]
