"""The primary interface as UR's docs site and client-interface pages list it: C-like rows.

    Joint data
    int packageSize
    unsigned char packageType = JOINT_DATA = 1
    for each joint:
    double q_actual
    ...
    end

A sub-package starts at `int packageSize`, a message at `int messageSize` (its type from
`messageType = NAME = n` and `robotMessageType = NAME = n`, its timestamp and source the
family's prefix); the title is the line before. "for each joint:" opens a group repeated
6 times, closed by "end" or, in the workbook's sheets (no "end"), by the first row no
longer indented; "(if X is installed, also the following:" opens a group present only
when X is, closed by a line ending in ")". `char array x` is a string; `(*)` marks rows
present only in some cases (read as rows). These pages have no version column.
"""

from __future__ import annotations

import re

from rtde_spec.importers.model import DocLayoutField, DocMember
from rtde_spec.importers.primary_text import key

_C_TYPES = {
    "unsigned char": "uint8",
    "char": "uint8",  # the document's byte, as the primary text form reads it
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
    rf"^({_TYPE})(?:\s+([A-Za-z_][A-Za-z0-9_]*))?(?:\[(\d*)\])?(?:\s*=\s*([A-Z_][A-Z0-9_]*)\s*=\s*(\d+)?)?;?$"
)
#: "uint8_t output mode": the PDF's names in words, read as one camelCase name
_WORDS = re.compile(rf"^({_TYPE})\s+([a-z][a-z0-9]*(?:\s+[a-z0-9]+){{1,5}})$")
#: a chapter of the document ("4. Control Modes"): the tables before it are over
_CHAPTER = re.compile(r"^\d+\.\s+[A-Z][A-Za-z ]+$")
#: "Following structure repeats for each running program thread": a group to the member's end
_REPEATS = re.compile(r"^following structure repeats\b", re.I)
#: the enum that names each type field's values: (field key, family) -> enum
TYPE_ENUMS = {
    "messagetype": "MessageType",
    "packagetype": "RobotStateSubPackageType",
    "robotmessagetype": "RobotMessageType",
    "robotmessagetype25": "ProgramStateMessageType",
}
_FOR_EACH = re.compile(r"^for each joint\s*:?$", re.I)
#: the global variables update's typed values, spelled out chunk by chunk: the spec's variable_values
_FOR_EACH_VARIABLE = re.compile(r"^for each variable\b", re.I)
_IF = re.compile(r"^\(?if (\w+)(?: interface)? is installed.*(?:following:?|also the)$", re.I)
#: whether a text is in this form: a package type given as NAME = number
SIGN = re.compile(r"packageType\s*=\s*[A-Z_]+\s*=\s*\d+")


def _prim(text: str) -> str:
    return _C_TYPES.get(text, text.removesuffix("_t"))


def _indent(raw: str) -> int:
    return len(raw) - len(raw.lstrip())


def _camel(words: str) -> str:
    first, *rest = words.split()
    return first + "".join(w[:1].upper() + w[1:] for w in rest)


def _number(name: str, field: str, family: int | None, enums: dict[str, dict[str, int]]) -> int | None:
    """A type's number from its name when the copy lost it ("MESSAGE_TYPE_ROBOT_MESSAGE ="): the
    spec's enum value whose name ends the document's name."""
    which = f"{field}{family}" if field == "robotmessagetype" and family == 25 else field
    table = enums.get(TYPE_ENUMS.get(which, ""))
    if not table:
        return None
    found = [v for n, v in table.items() if name == n or name.endswith("_" + n)]
    return found[0] if len(found) == 1 else None


def _joined(text: str) -> list[tuple[int, str, int]]:
    """Non-blank lines (number, text, indent); a name cut at an underscore continues on the next line
    ("ROBOT_MESSAGE_TYPE_PROGRAM_LABEL_" / "THREADS = 14" in the PDF's text)."""
    out: list[tuple[int, str, int]] = []
    for n, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        if out and out[-1][1].endswith("_") and re.match(r"^[A-Z0-9_]+\s*=", raw.strip()):
            last = out[-1]
            out[-1] = (last[0], last[1] + raw.strip(), last[2])
            continue
        cells = re.split(r"\s{3,}", raw.strip())
        if len(cells) > 1 and ROW.match(cells[0]):
            raw = raw[: len(raw) - len(raw.lstrip())] + cells[0]  # pdftotext -layout: Field, then Description
        out.append((n, raw.strip(), _indent(raw.replace("\u00a0", " "))))
    return out


def read_listing(text: str, enums: dict[str, dict[str, int]] | None = None) -> list[DocMember]:
    """Every sub-package and message listed in the C-like form, with its rows and groups.
    `enums` (the spec's type enums by name) give a type whose number the copy lost."""
    enums = enums or {}
    lines = _joined(text)
    members: list[DocMember] = []
    member: DocMember | None = None
    family: int | None = None
    group = ""
    block_indent: int | None = None  # the indent of a "for each joint:" block's first row
    in_message = False  # a message (messageSize): its rows start after robotMessageType
    block = 0  # counts "for each joint:" blocks: one row alone in one is an array of 6
    opened = 0  # the line of the open block's "for each joint:"
    values = False  # inside "for each variable:": the rest of the member is its typed values
    for_indent = 0  # the indent of the open block's "for each joint:" line
    pending: list[DocLayoutField] = []  # the open block's rows, until "end" or an indent shows its end

    def unclosed(at: int) -> None:
        """A block left open by neither "end" nor an indent: its extent is a guess; say so."""
        if member is not None and group == "repeat 6" and block_indent is None and opened:
            for row in pending:
                row.guessed = True
            member.notes.append(
                f"line {opened}: 'for each joint:' has no 'end' and its rows no indent: read as "
                f"repeated up to line {at}; where the block ends cannot be told"
            )

    for i, (number, text_line, indent) in enumerate(lines):
        line = re.sub(r"^\(\*\)\s*", "", text_line)  # (*): present only in some cases
        line = re.sub(r"\bchar ?array (\w+)", r"char \1[]", line, flags=re.I)  # the PDF: charArray
        line = re.sub(r"^(.*\w)\s*=\s*\d+\s*-\s*\d+$", r"\1", line)  # "requestedType = 0-8": its values
        # "(Used by Universal Robots software only)" after a row, also when the copy wraps it
        line = re.sub(r"\s*\(.*$", "", line) if ROW.match(line.split("(")[0].strip()) else line
        closes = line.endswith(")") and "(" not in line  # "short euromapCurrent)" ends an if-group
        if closes:
            line = line[:-1].rstrip()
        words = _WORDS.match(line)
        if words is not None and not ROW.match(line):
            line = f"{words.group(1)} {_camel(words.group(2))}"
        m = ROW.match(line)
        title = lines[i - 1][1] if i else "message"
        if m is not None and m.group(2) and key(m.group(2)) in ("messagesize", "packagesize"):
            unclosed(lines[i - 1][0] if i else number)
        if m is not None and m.group(2) and key(m.group(2)) == "messagesize":
            member = DocMember(title, None, None, lines[i - 1][0] if i else number)
            members.append(member)
            family, group, block_indent, in_message, values = None, "", None, True, False
            continue
        if m is not None and m.group(2) and key(m.group(2)) == "packagesize":
            member = DocMember(title, family or 16, None, lines[i - 1][0] if i else number)
            members.append(member)
            group, block_indent, in_message, values = "", None, False, False
            continue
        if m is not None and m.group(4) is not None:
            name = key(m.group(2) or "")
            number_ = int(m.group(5)) if m.group(5) else _number(m.group(4), name, family, enums)
            if number_ is None:
                continue
            if name == "messagetype":
                family = number_
                if member is not None and in_message:
                    member.family_type = family
            elif member is not None and member.member_type is not None and name == "packagetype":
                # the PDF's page layout moved a sub-package's type line below the next message:
                # it belongs to the last sub-package still without one
                late = next(
                    (x for x in reversed(members) if x.member_type is None and x.family_type == 16), None
                )
                if late is not None:
                    late.member_type = number_
            elif member is not None:
                member.member_type = number_
                in_message = False  # the family's prefix (timestamp, source) is behind
            continue
        if _CHAPTER.match(line) and "robot software" not in line.lower():
            unclosed(number)
            member, group = None, ""  # "4. Control Modes": the message tables are over
            continue
        if member is None or in_message or values:
            continue
        if group == "repeat 6" and block_indent is not None and indent < block_indent and line != "end":
            group, block_indent = "", None  # the workbook's block ends where the indent does
        if _REPEATS.match(line):
            group, block_indent = "repeat until_end", None
        elif _FOR_EACH_VARIABLE.match(line):
            # "for each variable: unsigned char valueType, one of the following chunks ...": one
            # field of typed values, as the spec reads it (variable_values), not a row per chunk
            member.fields.append(DocLayoutField("variableValues", "variablevalues", "bytes", "", number))
            values = True
        elif _FOR_EACH.match(line):
            unclosed(number)
            group, block_indent = "repeat 6", None
            for_indent = indent  # a row of the block is indented further than this line
            block += 1
            opened = number
            pending = []
        elif line.lower() == "end":
            group, block_indent = "", None
        elif (w := _IF.match(line)) is not None:
            # the group hangs on the row naming the interface ("char euromap67InterfaceInstalled")
            prev = member.fields[-1] if member.fields else None
            stem = key(w.group(1))
            named = prev is not None and prev.key.startswith(stem) and prev.key.endswith("installed")
            group = f"when {prev.key}" if named and prev is not None else f"when {stem}installed"
        elif m is not None and not m.group(2) and m.group(5) is None and "(" in text_line:
            # "uint32_t (Used by Universal Robots software only)": an unnamed field, the document's
            # reserved one (as the 5.x document names it)
            row = DocLayoutField("reserved", "reserved", _prim(m.group(1)), "", number, group)
            member.fields.append(row)
        elif m is not None and m.group(2):
            if group == "repeat 6" and block_indent is None:
                block_indent = indent if indent > for_indent else None
            type_ = _prim(m.group(1))
            if m.group(3) is not None:
                type_ = (
                    "string" if m.group(1) == "char" else f"{type_}[{m.group(3)}]" if m.group(3) else "bytes"
                )
            prev = member.fields[-1] if member.fields else None
            k = key(m.group(2))
            if type_ == "string" and prev is not None and prev.key in (k + "size", k + "length"):
                member.fields.pop()  # projectNameSize, then char array projectName: one field
                type_ = f"string({prev.type})"
            if not group and any(f.key == k and f.type == type_ and not f.group for f in member.fields):
                # the PDF repeats a table's last row at a page break ("uint16_t startIndex")
                member.notes.append(f"line {number}: {m.group(2)} listed again (a page break?): read once")
                continue
            row = DocLayoutField(m.group(2), k, type_, "", number, group)
            row.block = block if group == "repeat 6" else 0
            member.fields.append(row)
            if group == "repeat 6":
                pending.append(row)
            if closes:
                group = ""
        elif closes and group.startswith("when"):
            group = ""
    unclosed(lines[-1][0] if lines else 0)
    last = lines[-1][1] if lines else ""
    if member is not None and (m := ROW.match(last)) is not None and not m.group(2) and m.group(5) is None:
        # the copy ends inside a row ("unsigned char " and no name): this member is cut short
        member.cut = True
        member.notes.append(f"line {lines[-1][0]}: the copy ends inside a row of {member.title!r}: cut short")
    return [m for m in members if m.member_type is not None]
