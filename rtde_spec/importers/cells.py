"""Reading the cells of UR's field tables: names, types and "introduced in" versions.

The guides spell the same facts several ways over the years: `5.9.0`,
`5.23.0 / 10.11.0`, `[0..23] 3.4.0 [24..47] 3.9.0 / 5.3.0`, `3.3`, a version
followed by more text (`5.25.0 / 10.12.0 Is 3PE input active`), a version in the
comment column, `input_int_register_X (X=[0 .. 48])`, Rust type names (`u32`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rtde_spec.importers.model import VersionNote
from rtde_spec.metamodel.schema import Spec

#: the dashes a word processor puts where a range or a pair of versions has `..`, `-` or `/`
DASHES = "\u2010\u2011\u2012\u2013\u2014\u2212"
_SPAN = rf"\[\s*(\d+)\s*(?:\.\.|[-{DASHES}])\s*(\d+)\s*\]"
_TOKEN = re.compile(rf"({_SPAN})|(\d+\.\d+(?:\.\d+){{0,2}})|(/|;|,|[-{DASHES}])|(\S+)")
# a version expression inside free text: three-part versions only ("exceeds 1.0" is no version)
_IN_TEXT = re.compile(rf"(?:{_SPAN}\s*)?\d+\.\d+\.\d+(?:\s*[/{DASHES}]\s*\d+\.\d+\.\d+)*")
#: characters a copy puts inside names that no reader sees: zero-width space/joiners, soft
#: hyphen, byte-order mark, word joiner; they cut `actual_\u200bq` into `actual_`
INVISIBLE = re.compile("[\u00ad\u200b\u200c\u200d\u2060\ufeff]")


#: the ligatures a PDF's text layer gives for "fi", "fl", "ff" (a copy from a PDF viewer, pdftotext):
#: `conﬁgurable_digital_output` would be read as `con` and a field removed
_LIGATURES = str.maketrans(
    {
        "\ufb00": "ff",
        "\ufb01": "fi",
        "\ufb02": "fl",
        "\ufb03": "ffi",
        "\ufb04": "ffl",
        "\ufb05": "st",
        "\ufb06": "st",
    }
)


def visible(text: str) -> str:
    """The text without the invisible characters that would cut a name in two, its ligatures as
    the letters they stand for."""
    return INVISIBLE.sub("", text).translate(_LIGATURES)


_FAMILY = re.compile(r"^([A-Za-z0-9_]+?)_[Xx]\b\s*(?:\(\s*(?:X\s*=\s*)?" + _SPAN + r"\s*\))?")
_WORD = re.compile(r"[A-Za-z0-9_]+")


@dataclass(frozen=True)
class Lines:
    """Product lines by major version, and the spec's type names with their other spellings."""

    by_major: dict[int, str]
    types: dict[str, str]  # lower-case spelling -> spec type name

    @classmethod
    def of(cls, spec: Spec) -> Lines:
        by_major = {m: p.id for p in spec.product_lines.product_lines for m in p.majors}
        prims = {p.name: p for p in spec.primitives.primitives}
        types: dict[str, str] = {}
        for wire in spec.types.types:
            types[wire.name.lower()] = wire.name
            prim = prims.get(wire.element or "")
            if prim is None:
                continue
            # Rust spellings (u32, f64, bool, VECTOR6i32), derived from size, kind and sign
            bits = prim.size * 8
            rust = {"bool": "bool", "float": f"f{bits}"}.get(
                prim.kind, f"{'i' if prim.signed else 'u'}{bits}"
            )
            if wire.count == 1:
                types[rust] = wire.name
            else:
                types[wire.name.lower().replace(prim.name, rust)] = wire.name
        return cls(by_major, types)

    def line_of(self, version: str) -> str | None:
        return self.by_major.get(int(version.split(".")[0]))

    def type_name(self, text: str) -> str:
        """The spec's name for a type as a document writes it (unchanged if unknown)."""
        cleaned = text.strip().strip("`")
        return self.types.get(cleaned.lower(), cleaned)


def full_version(text: str) -> str:
    """3.3 -> 3.3.0; a build number is dropped."""
    parts = ([*text.split("."), "0", "0"])[:3]
    return ".".join(str(int(p)) for p in parts)


def parse_versions(text: str, lines: Lines) -> tuple[list[VersionNote], str]:
    """An "introduced in" cell: per index range the versions per line, and any text after them."""
    notes: list[VersionNote] = []
    span: tuple[int, int] | None = None
    current: dict[str, str] = {}
    rest = ""
    pending_span = False
    dashed = False  # "5.30.0 – 5.31.0": a range of versions; the first is the one introducing it
    for match in _TOKEN.finditer(text):
        marker, low, high, version, sep, word = match.groups()
        if marker:
            if current or pending_span:
                notes.append(VersionNote(span, current))
            span, current, pending_span = (int(low), int(high)), {}, True
        elif version:
            line = lines.line_of(version)
            if line is None:
                rest = text[match.start() :].strip()
                break
            if line in current and dashed:
                dashed = False
                continue
            if line in current:
                notes.append(VersionNote(span, current))
                current = {}
            current[line] = full_version(version)
            pending_span = dashed = False
        elif sep:
            dashed = sep not in "/;,"
            continue
        elif word:
            rest = text[match.start() :].strip()
            break
    if current:
        notes.append(VersionNote(span, current))
    return notes, rest


def versions_in_text(text: str, lines: Lines) -> tuple[list[VersionNote], str]:
    """Versions written into a comment (an earlier edition's merged columns); the text without them."""
    found = list(_IN_TEXT.finditer(text))
    if not found:
        return [], text
    notes: list[VersionNote] = []
    for match in found:
        notes += parse_versions(match.group(0), lines)[0]
    stripped = _IN_TEXT.sub(" ", text)
    return notes, " ".join(stripped.split()).strip(" -;,")


#: what a copy puts around a name: Markdown's `code` and **bold**, quotes (straight or typographic)
NAME_MARKS = "`*'\"\u2018\u2019\u201c\u201d"


#: a line break beside a `_` inside a name cell (`speed_<br>slider_mask` in a saved page's narrow
#: column): no name ends or starts with `_`, so the parts are one name (see `wrapped`)
_BROKEN_AT_UNDERSCORE = re.compile(r"(?<=\w_)\s+(?=\w)|(?<=\w)\s+(?=_\w)")


def name_text(cell: str) -> str:
    """A name cell's text without the marks around the name, a name broken beside a `_` rejoined."""
    return _BROKEN_AT_UNDERSCORE.sub("", visible(cell).strip().strip(NAME_MARKS).strip())


def parse_name(cell: str) -> tuple[str, tuple[int, int] | None, bool]:
    """(name with {X}, index range written in the name, is it a family) of a name cell."""
    text = name_text(cell)
    match = _FAMILY.match(text)
    if match and (match.end() == len(text) or text[match.end() :].strip() == ""):
        base, low, high = match.group(1), match.group(2), match.group(3)
        span = (int(low), int(high)) if low is not None else None
        return f"{base}_{{X}}", span, True
    word = _WORD.match(text)
    return (word.group(0) if word else text), None, False


def spans_in(text: str) -> list[tuple[int, int]]:
    """Every [a..b] of a comment (the register ranges a family's comment names)."""
    return [(int(a), int(b)) for a, b in re.findall(_SPAN, text)]


def words(text: str) -> set[str]:
    """The meaningful words of a description, stemmed, for telling a rewording from a change.

    Numbers, index ranges and bracketed units are left out: the spec keeps those in
    their own keys (index, ranges, unit).
    """
    text = re.sub(_SPAN, " ", text)
    text = re.sub(r"\[[^\]]*\]", " ", text)
    stop = {
        "a",
        "an",
        "the",
        "of",
        "in",
        "is",
        "are",
        "and",
        "or",
        "to",
        "for",
        "by",
        "with",
        "this",
        "that",
        "it",
        "be",
        "as",
        "on",
        "at",
        "from",
        "given",
        "i",
        "e",
        "g",
        "when",
        "if",
        "one",
        "use",
        "using",
        "used",
        "can",
        "value",
        "values",
        "its",
        "which",
        "into",
        "where",
    }
    stop |= {"general", "purpose", "actually", "currently", "current", "robot", "controller", "degrees"}
    found = (w for w in re.findall(r"[a-z]+", text.lower()) if w not in stop and len(w) > 1)
    return {w[:-1] if w.endswith("s") and len(w) > 3 else w for w in found}
