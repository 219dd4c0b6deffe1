"""Read UR's published documents (RTDE guides, the primary interface document) and diff them.

Imported only by `rtde-spec spec import`: nothing here runs at CLI start-up.
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path

from rtde_spec.errors import UsageError
from rtde_spec.importers import columns_text, html_doc, markdown, realtime_tables, rendered_text
from rtde_spec.importers.cells import Lines, visible
from rtde_spec.importers.edition import newest, versions_named
from rtde_spec.importers.model import Document, check_source
from rtde_spec.importers.rows import field_rows, main_line, merged_rows, odd_names
from rtde_spec.importers.side_by_side import unfold_tables
from rtde_spec.importers.sniff import ZIP, refuse_binary, utf16_without_bom
from rtde_spec.importers.tables import MAX_BYTES
from rtde_spec.metamodel.document_forms import FORMATS
from rtde_spec.metamodel.schema import Spec
from rtde_spec.metamodel.versions import Version

#: what a document must hold to be read, for the error when none is found
LOOKED_FOR = (
    "an RTDE field table (header cells Name, Type, Comment[, Introduced in version] under a heading "
    "naming inputs or outputs), a real-time interface table (Meaning, Type, Number of values, "
    "Size in bytes) or the primary interface's sub-package tables"
)
_DEFAULT_SOURCE = {
    "cb3-text": "cb3-guide",
    "e-series-text": "e-series-guide",
    "primary-text": "primary-guide",
}
#: the real-time table's header as paragraphs (rendered) or cells ending in `|`
_REALTIME_HEAD = re.compile(
    r"^[ \t]*Meaning[ \t]*\|?[ \t]*\n(?:[ \t]*\n)*[ \t]*Type[ \t]*\|?[ \t]*\n(?:[ \t]*\n)*"
    r"[ \t]*Number of\s+values",  # the PDF's text wraps the cell: "Number of" / "values"
    re.M | re.I,
)


#: a Markdown table without its outer pipes: `Name | Type | ...` over a `---|---` ruler
_BARE_MD = re.compile(r"^[ \t]*(?:Name|Meaning|Field)[ \t]*\|[^\n]*\n[ \t]*\|?[ \t]*:?-{3,}", re.M)


def detect_format(text: str) -> str:
    """Which of UR's document forms this is, from its content alone."""
    head = text[:4096].lower()
    if "<table" in text.lower() or head.lstrip().startswith(("<!doctype html", "<html")):
        return "html"
    if re.search(r"^\s*\|\s*(Name|Meaning|Field)\s*\|", text, re.M) or _BARE_MD.search(text):
        return "markdown"
    if "ROBOT_STATE_PACKAGE_TYPE" in text or "Sub Package of Robot State" in text:
        return "primary-text"
    from rtde_spec.importers.primary_listing import SIGN

    if SIGN.search(text):
        return "primary-text"
    if _REALTIME_HEAD.search(text) or realtime_tables.SPACED_HEAD.search(text):
        return "rendered-text"
    if re.search(r"^\s*Name\s*\|\s*$", text, re.MULTILINE):
        return "e-series-text"
    if re.search(r"^\s*Name\tType\t", text, re.MULTILINE):
        return "cb3-text" if _cb3_era(text) else "tab-text"
    if columns_text.SIGN.search(text):
        return "columns-text"
    if rendered_text.HEADER.search(text):
        return "rendered-text"
    raise UsageError(
        "cannot tell the document's form: expected an RTDE guide (tab-separated text, "
        "pipe-terminated text, rendered text with a cell per line, columns aligned with spaces as "
        "pdftotext -layout gives them, Markdown or HTML tables, the client-interface .xlsx) or the "
        "primary interface document; --form names the form"
    )


#: a version in a tab-separated cell, by major: 3.x is the CB3 guide's, 5.x/10.x the e-Series guide's
_TAB_VERSION = re.compile(r"\t[^\t\n]*?(?<![\d.])(3|5|10)\.\d+(?:\.\d+)?(?![\d.])")


def _cb3_era(text: str) -> bool:
    """Whether tab-separated tables are the CB3-era guide's, not the e-Series guide copied from a
    browser (which comes as tabs too): the CB3 guide's version cells name 3.x (3.3, [0..23] 3.4.0),
    the e-Series guide's 5.x and 10.x; its prose says 500 Hz and e-Series, the CB3 guide's 125 Hz."""
    majors = [m.group(1) for m in _TAB_VERSION.finditer(text)]
    cb3 = majors.count("3")
    newer = len(majors) - cb3
    if cb3 != newer:
        return cb3 > newer
    return not re.search(r"\b500\s*Hz\b|\be-Series\b", text, re.I)


#: the source id of an RTDE guide by the product line it is written for: recorded conflicts are
#: keyed to it, so the same guide saved under another file name must get the same id
_GUIDE_SOURCE = {"cb3": "cb3-guide", "e-series": "e-series-guide", "polyscope-x": "e-series-guide"}


#: what only UR's RTDE guide says: its tables' headings and its title (a client's README has others)
_GUIDE_SIGN = re.compile(r"\brobot controller (?:in|out)puts\b|\(RTDE\) Guide\b", re.I)


def _is_guide(doc: Document, text: str) -> bool:
    """Whether the document is UR's RTDE guide in some copy, not another list of fields."""
    return any(_GUIDE_SIGN.search(t.heading) for t in doc.tables) or bool(_GUIDE_SIGN.search(text[:4096]))


def _slug(path: Path) -> str:
    return re.sub(r"[^a-z0-9]+", "-", path.stem.lower()).strip("-") or "document"


def edition_of(doc: Document) -> str | None:
    """The newest version of the document's own line that its version cells name: the document is
    at least that edition, and cannot speak of fields introduced after it."""
    found = [
        Version.parse(v)
        for f in doc.fields
        for note in f.notes
        for line, v in note.versions.items()
        if line == doc.line and v
    ]
    return str(max(found)) if found else None


def _text(path: Path) -> str:
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise UsageError(f"{path}: {size} bytes; UR's documents are under {MAX_BYTES} bytes")
        data = path.read_bytes()
        refuse_binary(data, path)
        # lone CRs end lines too: Excel for Mac's "tab-delimited text" writes them
        return visible(decode(data, path)).replace("\r\n", "\n").replace("\r", "\n")
    except FileNotFoundError:
        raise UsageError(f"no such document: {path}") from None
    except IsADirectoryError:
        raise UsageError(f"{path} is a directory, not a document") from None


_BOMS = (
    (codecs.BOM_UTF8, "utf-8-sig"),
    (codecs.BOM_UTF32_LE, "utf-32"),  # before UTF-16's: FF FE 00 00 starts with UTF-16 LE's FF FE
    (codecs.BOM_UTF32_BE, "utf-32"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
)
#: `<meta charset="windows-1252">` or `<meta http-equiv="Content-Type" content="text/html; charset=...">`
_CHARSET = re.compile(rb"<meta\b[^>]*?charset\s*=\s*[\"']?\s*([A-Za-z0-9_.:-]+)", re.I)


def decode(data: bytes, path: Path | str = "") -> str:
    """The document's text in the charset it declares: a byte-order mark first, then an HTML
    `<meta>` charset; else UTF-8, and Windows-1252 (what a Windows browser's "save as" writes)
    only when the bytes are no UTF-8. Reading a cp1252 page as UTF-8 would put U+FFFD in names."""
    for bom, codec in _BOMS:
        if data.startswith(bom):
            return _decode_as(data, codec, path, "its byte-order mark")
    declared = _CHARSET.search(data[:4096])
    if declared is not None:
        name = declared.group(1).decode("ascii", "replace").lower()
        try:
            codec = codecs.lookup(name).name
        except LookupError:
            codec = ""
        if codec and not codec.startswith("utf-16"):  # a UTF-16 page without a BOM lies
            # browsers read a page declared latin-1/ascii as windows-1252 (the WHATWG rule)
            codec = "cp1252" if codec in ("latin-1", "iso8859-1", "ascii") else codec
            return _decode_as(data, codec, path, f"its <meta> charset {name!r}")
    bare = utf16_without_bom(data)
    if bare is not None:
        return _decode_as(data, bare, path, "its NUL bytes (UTF-16 without a byte-order mark)")
    if b"\0" in data:
        raise UsageError(f"{path}: binary data (a NUL byte at offset {data.index(0)}), not a text document")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("cp1252", errors="replace")


def _decode_as(data: bytes, codec: str, path: Path | str, why: str) -> str:
    try:
        return data.decode(codec)
    except UnicodeDecodeError as exc:
        raise UsageError(
            f"{path}: not {codec} as {why} says (byte {exc.start}: {data[exc.start : exc.start + 1]!r}); "
            "save the document as UTF-8"
        ) from None


def _starts(path: Path, magic: bytes) -> bool:
    """Whether the file begins with `magic` (a workbook saved as Client_Interface.xls is a ZIP)."""
    try:
        with path.open("rb") as f:
            return f.read(len(magic)) == magic
    except OSError:
        return False  # said by the reader that opens it next


def read_document(
    path: Path | str,
    spec: Spec,
    source: str | None = None,
    line: str | None = None,
    fmt: str | None = None,
    edition: str | None = None,
) -> Document:
    """Read a document in any supported form into the common model."""
    path = Path(path)
    if source is not None:
        check_source(source)
    if fmt not in (None, *FORMATS):
        raise UsageError(f"unknown form {fmt!r}; one of {', '.join(FORMATS)}")
    if fmt == "xlsx" or (fmt is None and (path.suffix.lower() in (".xlsx", ".xlsm") or _starts(path, ZIP))):
        from rtde_spec.importers.workbook import read_workbook

        return read_workbook(path, spec, source, line, edition)
    text = _text(path)
    try:
        kind = fmt or detect_format(text)
    except UsageError as exc:  # which file could not be told, as every other read error says
        raise UsageError(str(exc), subject=f"file {path}") from None
    lines = Lines.of(spec)
    doc = Document(str(path), kind, source or _DEFAULT_SOURCE.get(kind) or _slug(path))
    if kind == "primary-text":
        from rtde_spec.importers.primary_text import lost_arrows, read_members

        doc.members = read_members(text, lines)
        if lost := lost_arrows(text):
            doc.remarks.append(
                f"lines {', '.join(map(str, lost[:5]))}{'…' if len(lost) > 5 else ''}: "
                "a group's row starts with '?' or the like, read as its '→' (an 8-bit save)"
            )
        if not doc.members:  # the docs site's C-like listing ("for each joint: ... end")
            from rtde_spec.importers.primary_listing import read_listing

            doc.members = _newest_section(read_listing(text, _type_enums(spec)), text, doc)
            if source is None and not re.search(r"Robot Software \d", text):
                # the C-like listing is the client-interface workbook's form; the interface
                # document (ClientInterfaces_Primary.pdf as text) uses it too, under "Robot Software 5.x"
                doc.source = "client-interface-workbook"
        if not doc.members:
            raise UsageError(
                f"{path}: no message table read; looked for the primary interface's sub-package "
                "tables (a title naming the package type, then Field/Description[/Introduced in "
                "version] rows, or the C-like listing: int packageSize, packageType = NAME = n)"
            )
        named = versions_named(text, lines)
        doc.line = line or _text_line(named) or "e-series"
        doc.edition = str(Version.parse(edition)) if edition else named.get(doc.line)
        return doc
    if kind in ("cb3-text", "tab-text", "e-series-text", "rendered-text", "columns-text"):
        from rtde_spec.importers.text_tables import read_text_tables

        tables = read_text_tables(kind, text, doc, lines, spec)
        if kind in ("e-series-text", "rendered-text"):
            links = realtime_tables.chapter_titles(text)
            doc.realtime = (
                realtime_tables.read_paragraphs(text, lines, links)
                or realtime_tables.read_paragraphs(realtime_tables.joined_cells(text), lines, links)
                or realtime_tables.read_spaced(text, lines)
            )
    elif kind == "markdown":
        tables = markdown.read_tables(text)
    else:
        tables = html_doc.read_tables(text, doc.problems)
    if kind in ("markdown", "html", "cb3-text", "tab-text"):
        doc.realtime = realtime_tables.tables_in(tables, lines)
        doc.members = _primary_tables(tables, lines)
        if doc.members and source is None:
            doc.source = "primary-guide"
    if doc.realtime and source is None:
        doc.source = "realtime-guide"
    default = "cb3" if kind == "cb3-text" else "e-series"
    finish(doc, tables, lines, line, edition, default, text, spec)
    if source is None and doc.fields and not doc.realtime and not doc.members and _is_guide(doc, text):
        # the guide's own id whatever the file is called (guide (1).html, rtde.md): decided by the
        # line it is written for, as when the seed is imported, so recorded conflicts still match
        doc.source = _GUIDE_SOURCE.get(doc.line, doc.source)
    return doc


def _primary_tables(tables: list, lines: Lines) -> list:
    """The primary interface's tables of an HTML or Markdown copy (Field | Description[ |
    Introduced in version]), read as the rendered text form is: a title, then a cell per line."""
    from rtde_spec.importers.primary_text import read_members

    found = [t for t in tables if [h.strip().lower() for h in t.header[:2]] == ["field", "description"]]
    if not found:
        return []
    parts = []
    for t in found:
        cells = [c.strip() for _, row in t.rows for c in row if c.strip()]
        parts.append("\n".join([t.heading or "table", *[h.strip() for h in t.header if h.strip()], *cells]))
    return read_members("\n".join(parts), lines)


_SECTION = re.compile(r"^\s*\d+\.\s+Robot Software (\d+\.\d+(?:\.\d+)?)\s*$", re.M)


def _newest_section(members: list, text: str, doc: Document) -> list:
    """The members of the newest "N. Robot Software X.Y" section when a document holds several
    editions (ClientInterfaces_Primary.pdf: 5.9 and 5.10); the older sections are reported. A
    member belongs to the last section heading (or page header naming one) above it."""
    starts = [(text.count("\n", 0, m.start()) + 1, m.group(1)) for m in _SECTION.finditer(text)]
    if len({v for _, v in starts}) < 2:
        return members

    def section(line: int) -> str | None:
        found = [v for at, v in starts if at <= line]
        return found[-1] if found else None

    by = {id(m): section(m.line) for m in members}
    editions = {v for v in by.values() if v}
    if len(editions) < 2:
        return members
    newest = max(editions, key=Version.parse)
    for edition in sorted(editions - {newest}, key=Version.parse):
        count = sum(1 for v in by.values() if v == edition)
        doc.remarks.append(
            f"section 'Robot Software {edition}': {count} message tables of an older edition in the "
            f"same document, not compared (the {newest} section is)"
        )
    return [m for m in members if by[id(m)] == newest]


def _type_enums(spec: Spec) -> dict[str, dict[str, int]]:
    """The spec's enums of message and sub-package types, by name: a copy that lost a number."""
    from rtde_spec.importers.primary_listing import TYPE_ENUMS

    wanted = set(TYPE_ENUMS.values())
    return {e.name: {v.name: v.value for v in e.values} for e in spec.all_enums if e.name in wanted}


def _text_line(named: dict[str, str]) -> str | None:
    """The product line a text names software versions of, when it names only one."""
    return next(iter(named)) if len(named) == 1 else None


def listed_edition(doc: Document, spec: Spec | None) -> str | None:
    """The newest first version (on the document's line) of the spec fields the document lists:
    a copy listing actual_TCP_acceleration (5.23.0) with a blank cell is at least 5.23.0."""
    if spec is None:
        return None
    from rtde_spec.importers.scope import first_versions

    entries = {
        (e.name, d): e
        for d, es in (("input", spec.fields.inputs), ("output", spec.fields.outputs))
        for e in es
    }
    found = [
        v
        for f in doc.fields
        if (entry := entries.get((f.name, f.direction))) is not None
        for v in first_versions(entry, doc.line, spec)[:1]
    ]
    return newest(*found)


def finish(
    doc: Document,
    tables: list,
    lines: Lines,
    line: str | None,
    edition: str | None,
    default: str,
    text: str = "",
    spec: Spec | None = None,
) -> Document:
    """Fields of the tables into `doc`, its line and edition; exit 2 when no table of any
    interface (RTDE fields, real-time rows, primary sub-packages) is read."""
    tables = unfold_tables(tables, doc.problems)
    doc.fields = field_rows(tables, lines, doc.tables)
    doc.problems += merged_rows(doc.fields, lines) + odd_names(tables)
    for table in tables:
        if table.is_field_table and table.direction is None and table.rows:
            # never dropped silently: a table the copy does not say the direction of (a heading
            # naming neither or both) is not compared, and the spec's fields would look removed
            doc.problems.append(
                f"the field table at line {table.line} ({len(table.rows)} rows, heading "
                f"{table.heading or 'none'!r}) names no direction (inputs or outputs): not read"
            )
    if not doc.fields and not doc.realtime and not doc.members:
        seen = f" ({len(tables)} other tables seen)" if tables else ""
        why = "".join(f"; {problem}" for problem in doc.problems)  # a field table of no direction: where
        raise UsageError(f"{doc.path} ({doc.format}): no field read{seen}; looked for {LOOKED_FOR}{why}")
    named = versions_named(text, lines)
    if doc.fields:
        doc.line = line or main_line(doc.fields, _text_line(named) or default)
    elif line or not doc.line:
        realtime = next((t.product_line for t in doc.realtime if t.product_line), None)
        doc.line = line or realtime or _text_line(named) or default
    if edition:
        doc.edition = str(Version.parse(edition))
    elif doc.fields:
        doc.edition = newest(edition_of(doc), named.get(doc.line), listed_edition(doc, spec))
    elif not doc.edition:
        doc.edition = named.get(doc.line)
    return doc
