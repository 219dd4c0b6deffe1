"""What a published document says, in one shape whatever its format.

Each format reader (CB3-era text, e-Series-era text, Markdown, HTML, the primary
interface text) produces these; the diff modules compare them with the spec.
"""

from __future__ import annotations

from dataclasses import dataclass, field

#: (low, high) inclusive register index range, or None for the whole field
IndexSpan = tuple[int, int] | None


@dataclass
class VersionNote:
    """One part of an "introduced in" cell: the versions per product line for an index range."""

    span: IndexSpan
    versions: dict[str, str]  # product line id -> version


@dataclass
class DocField:
    """One row of an RTDE field table."""

    name: str  # a family keeps {X} in its name
    direction: str  # input | output
    type: str  # as normalised to a spec type name when it matches one, else as written
    doc: str
    line: int  # 1-based line of the document the row starts on
    index: tuple[int, int] | None = None
    notes: list[VersionNote] = field(default_factory=list)
    version_text: str = ""  # the cell as written, for the report


@dataclass
class DocLayoutField:
    """One row of a primary-interface message table (groups flattened to a path)."""

    name: str
    key: str  # the name normalised to match the spec's snake_case
    type: str  # a primitive, "string", "bytes", "switch", or "" when the document gives none
    doc: str
    line: int
    group: str = ""  # the repeated or conditional group the row belongs to
    versions: dict[str, str] = field(default_factory=dict)
    version_text: str = ""
    block: int = 0  # which "for each joint:" block of the member the row is in (0: none)
    guessed: bool = False  # in a block whose end the copy does not show: its group is a guess


@dataclass
class DocMember:
    """A message or sub-package of the primary document."""

    title: str
    family_type: int | None
    member_type: int | None
    line: int
    fields: list[DocLayoutField] = field(default_factory=list)
    versions: dict[str, str] = field(default_factory=dict)  # "introduced in" of the header rows
    notes: list[str] = field(default_factory=list)  # what the reader could not tell for sure
    cut: bool = False  # the copy ends inside it: fields after its last row are not compared


@dataclass
class TableReport:
    """What one table of the document gave: rows read, fields kept, placeholder rows skipped."""

    heading: str
    direction: str
    line: int
    rows: int = 0
    fields: int = 0
    skipped: list[tuple[int, str]] = field(default_factory=list)  # (line, cell) of placeholder rows
    names: list[str] = field(default_factory=list)  # the fields read from it
    cut: bool = False  # the copy ends inside it: the spec fields it does not list are not removals


@dataclass
class DocRealtimeRow:
    """One row of a real-time interface table: Meaning | Type | Number of values | Size in bytes."""

    name: str  # as written ("q target"); "" for the rows UR leaves unnamed (reserved)
    key: str  # the name as the spec spells it (q_target); "" when unnamed
    type: str  # as written, lower case (double, integer)
    count: int
    size: int  # bytes, as the document gives them
    doc: str
    line: int
    column: str = ""  # the Gnuplot column as written ("2 - 7")


@dataclass
class DocRealtimeTable:
    """One edition's real-time message table (RealTime 5.10, the workbook's RealTime_3.2 sheet)."""

    title: str
    line: int
    edition: str | None  # the version its title names (the table is the message of that version)
    product_line: str | None  # the line of that version; None: a version no line covers (1.x)
    header: list[DocRealtimeRow] = field(default_factory=list)  # Message Size
    rows: list[DocRealtimeRow] = field(default_factory=list)
    total: tuple[int, int] | None = None  # (values, bytes) of its TOTAL row
    skipped: list[tuple[int, str]] = field(default_factory=list)  # rows that are no field
    #: rows (the TOTAL's too) whose numbers are not there: a workbook's formulas saved without values
    unread: list[tuple[int, str]] = field(default_factory=list)


@dataclass
class Document:
    """A document as read: its format, the product line it speaks for, and its tables."""

    path: str
    format: str  # cb3-text | tab-text | e-series-text | rendered-text | markdown | html | xlsx | primary-text
    source: str  # the id recorded in `sources` (cb3-guide, e-series-guide, ...)
    line: str = ""  # the product line whose versions the document lists first
    fields: list[DocField] = field(default_factory=list)
    members: list[DocMember] = field(default_factory=list)
    tables: list[TableReport] = field(default_factory=list)
    edition: str | None = None  # the newest version the document speaks of (its text, or --edition)
    #: spec fields a table that stops early (a placeholder row) leaves out: direction -> names
    unlisted: dict[str, list[str]] = field(default_factory=dict)
    remarks: list[str] = field(default_factory=list)  # what was read but is no change (blank/CB3-only cells)
    realtime: list[DocRealtimeTable] = field(default_factory=list)  # real-time interface tables
    #: what makes the reading incomplete (the copy ends inside a table, a table with no direction):
    #: --check and --write refuse while there are any, since "0 removed" would not be true
    problems: list[str] = field(default_factory=list)

    @property
    def interfaces(self) -> list[str]:
        """The interfaces the document has tables of: rtde, primary, realtime."""
        found = [("rtde", self.fields), ("primary", self.members), ("realtime", self.realtime)]
        return [name for name, what in found if what]

    @property
    def interface(self) -> str:
        """The one interface of the document (the first read when it holds several)."""
        found = self.interfaces
        return found[0] if found else ("primary" if self.format == "primary-text" else "rtde")


def check_source(source: str) -> None:
    """Refuse a --source the spec cannot record (the schema's `Source` pattern), before any reading:
    it was accepted until --write's checked copy of the spec failed, and recorded conflicts never
    matched it meanwhile."""
    from pydantic import TypeAdapter, ValidationError

    from rtde_spec.errors import UsageError
    from rtde_spec.metamodel.schema import Source

    try:
        TypeAdapter(Source).validate_python(source)
    except ValidationError as exc:
        pattern = exc.errors()[0].get("ctx", {}).get("pattern", "")
        raise UsageError(
            f"--source {source!r}: a source id is lower-case letters, digits, '.' and '-', starting "
            f"with a letter or digit (the pattern {pattern}), as the spec records it"
        ) from None
