"""The primary/secondary interface document as text: a table per message and sub-package.

Each table is `Field | Description | Introduced in version` flattened to one cell
per line: `type name` rows (`double DHa[6]`, `char buildDate[]`, `→ ` inside a
group), description lines, and version lines. "Following N fields are repeated for
each joint (6 times)", "... present only if X is true" and "Following structure
repeats ..." open groups; "Following data type depends on this value" a switch.
"""

from __future__ import annotations

import re

from rtde_spec.importers.cells import Lines, parse_versions
from rtde_spec.importers.model import DocLayoutField, DocMember
from rtde_spec.importers.tables import is_page_line, running_lines

_TYPES = r"unsigned char|uint\d+_t|int\d+_t|double|float|bool|char|type32"
#: the arrow that marks a group's rows, and what it becomes in a copy saved in an 8-bit code page
#: (Windows-1252, Latin-1: "?"), read back in the wrong one ("â†’"), or typed ("->")
ARROWS = r"→|\?|â†’|â\x86\x92|->"
_ROW = re.compile(rf"^((?:{ARROWS})\s*)?(?:({_TYPES})\s+)?([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d*)\])?$")
_LOST_ARROW = re.compile(
    rf"^[ \t]*(?!→)(?:{ARROWS})[ \t]*(?:{_TYPES})[ \t]+[A-Za-z_]\w*(?:\[\d*\])?[ \t]*$", re.M
)


def lost_arrows(text: str) -> list[int]:
    """Lines whose group arrow is not "→" (a "?" where an 8-bit save had no arrow): read as the arrow."""
    return [text.count("\n", 0, m.start()) + 1 for m in _LOST_ARROW.finditer(text)]


_VERSION_LINE = re.compile(r"^\d+\.\d+\.\d+(\s*/\s*\d+\.\d+\.\d+)*(\s.*)?$")
_NUMBER = re.compile(r"^[A-Z][A-Z0-9_]* = (\d+)$")
_REPEAT = re.compile(r"^Following \d+ fields are repeated .*\((\d+) times\)", re.IGNORECASE)
_WHEN = re.compile(r"^Following \d+ fields are present only if (\w+) is true", re.IGNORECASE)
_HEADER_ROWS = {"messagesize", "messagetype", "packagesize", "packagetype"}


def key(name: str) -> str:
    """A name as both sides can agree on: isRealRobotConnected == is_real_robot_connected."""
    flat = name.replace("_", "").lower()
    return "reserved" if re.fullmatch(r"reserved\d*", flat) else flat


def _prim(type_text: str) -> str:
    if type_text in ("char", "unsigned char"):
        return "uint8"  # the document's byte; robotMessageType is char in one table, uint8_t in others
    return type_text.removesuffix("_t")


_HEAD = ["field", "description"]
_VERSION_HEAD = re.compile(r"(introduced in )?version|since", re.I)
_FOR_EACH = re.compile(r"^for each joint\s*:?$", re.I)


def _head_size(numbered: list[tuple[int, str]], at: int) -> int:
    """Lines of the table header starting at `at`: Field, Description[, Introduced in version]; 0: none.

    The docs site's 5.9 edition has no version column; the manual's has one.
    """
    if [t.lower() for _, t in numbered[at : at + 2]] != _HEAD:
        return 0
    return 3 if at + 2 < len(numbered) and _VERSION_HEAD.fullmatch(numbered[at + 2][1]) else 2


def _title(lines: list[tuple[int, str]], at: int) -> int:
    """The index of a table's title: the nearest line before it that is not a sentence."""
    for j in range(at - 1, -1, -1):
        text = lines[j][1]
        if not text.endswith(".") and len(text) <= 90 and not _ROW.match(text):
            return j
    return at


class _Builder:
    """Collects one member's rows: groups, switches, length prefixes, versions, descriptions."""

    def __init__(self, member: DocMember, lines: Lines) -> None:
        self.member = member
        self.lines = lines
        self.group = ""
        self.in_switch = False
        self.switch_seen = False
        self.prefix_done = False
        self.last_header = ""
        self.last_row_line = -1
        self.after_header = False
        self.rows: list[DocLayoutField] = []
        self.block = ""  # a "for each joint: ... end" block: its rows are the 6-times group

    def text(self, number: int, text: str) -> None:
        if (m := _REPEAT.match(text)) is not None:
            self.group, self.in_switch = f"repeat {m.group(1)}", False
        elif (m := _WHEN.match(text)) is not None:
            self.group, self.in_switch = f"when {key(m.group(1))}", False
        elif text.lower().startswith("following structure repeats"):
            self.group, self.in_switch = "repeat until_end", False
        elif text.lower().startswith("following data type depends"):
            self.in_switch, self.switch_seen = True, False
        elif (m := _NUMBER.match(text)) is not None and self.last_header:
            number_value = int(m.group(1))
            if self.last_header == "messagetype":
                self.member.family_type = number_value
            elif self.last_header == "packagetype":
                self.member.family_type = self.member.family_type or 16
                self.member.member_type = number_value
                self.prefix_done = True
            else:
                self.member.member_type = number_value
                self.prefix_done = True
            self.last_header = ""
        elif _VERSION_LINE.match(text) and (self.rows or self.after_header):
            notes, _ = parse_versions(text, self.lines)
            target = self.member.versions if self.after_header else self.rows[-1].versions
            for note in notes:
                target.update(note.versions)
            if not self.after_header:
                self.rows[-1].version_text = text
        elif re.match(r"^\d+(,\d+)*:", text):
            pass  # a switch case ("0,1:uint32_t"), not a description
        elif self.rows and self.rows[-1].line == self.last_row_line:
            self.rows[-1].doc = text  # the first line after a row is its description
            self.last_row_line = -1

    def row(self, number: int, arrow: bool, type_text: str | None, name: str, count: str | None) -> None:
        k = key(name)
        self.after_header = k in _HEADER_ROWS
        if not arrow:
            self.group, self.in_switch = self.block, False
        if k in _HEADER_ROWS or k == "robotmessagetype":
            self.last_header = k
            if self.member.family_type == 16 and k == "packagetype":
                self.prefix_done = False
            return
        if not self.prefix_done and self.member.family_type not in (None, 16):
            return  # timestamp, source: the family's prefix
        if self.in_switch and arrow:
            if not self.switch_seen:
                self.switch_seen = True
                self._add(number, "switch", name)
            return  # a case's own rows (5:String -> textLength, textMessage[])
        if type_text is None:
            type_ = "bytes" if k == "reserved" else ""
        elif count is not None:
            type_ = (
                "string"
                if type_text == "char"
                else "bytes"
                if count == ""
                else f"{_prim(type_text)}[{count}]"
            )
        else:
            type_ = _prim(type_text)
        prev = self.rows[-1] if self.rows else None
        if type_ == "string" and prev is not None and prev.key in (k + "length", k + "size"):
            self.rows.pop()  # a length prefix and its text are one field
            type_ = f"string({prev.type})"
        self._add(number, type_, name)

    def _add(self, number: int, type_: str, name: str) -> None:
        self.rows.append(DocLayoutField(name, key(name), type_, "", number, self.group))
        self.last_row_line = number


def read_members(text: str, lines: Lines) -> list[DocMember]:
    """Every message and sub-package table of the document, with its rows."""
    numbered = [(n, raw.strip()) for n, raw in enumerate(text.splitlines(), start=1) if raw.strip()]
    # a printed page's furniture (its footer with the page number, the running title) is no row's
    # description: "Copyright © … Page 3 of 40" was read as requestedType's
    running = running_lines([t for _, t in numbered])
    numbered = [(n, t) for n, t in numbered if not is_page_line(t) and t not in running]
    members: list[DocMember] = []
    builder: _Builder | None = None
    heads = {i: _head_size(numbered, i) for i in range(len(numbered))}
    heads = {i: n for i, n in heads.items() if n}
    titles = {_title(numbered, h): h for h in heads}  # title index -> its header index
    i = 0
    while i < len(numbered):
        number, line = numbered[i]
        if i in titles:
            if builder is not None:
                builder.member.fields = builder.rows
            member = DocMember(line, None, None, number)
            members.append(member)
            builder = _Builder(member, lines)
            i = titles[i] + heads[titles[i]]
            continue
        if builder is not None:
            if _FOR_EACH.match(line):
                builder.block = "repeat 6"  # 5.23's "for each joint: ... end"
            elif line.lower() == "end" and builder.block:
                builder.block = ""
            elif line.endswith(":") and not re.match(r"^\d+(,\d+)*:", line) and len(line) <= 40:
                builder.member.fields = builder.rows  # "Data types:": the tables that follow are not fields
                builder = None
            elif (m := _ROW.match(line)) is not None and (m.group(2) or m.group(3).lower() == "reserved"):
                builder.row(number, bool(m.group(1)), m.group(2), m.group(3), m.group(4))
            else:
                builder.text(number, line)
        i += 1
    if builder is not None:
        builder.member.fields = builder.rows
    return [m for m in members if m.member_type is not None]
