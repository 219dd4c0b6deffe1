"""Read UR's published documents (RTDE guides, the primary interface document) and diff them.

Imported only by `rtde-spec spec import`: nothing here runs at CLI start-up.
"""

from __future__ import annotations

import re
from pathlib import Path

from rtde_spec.errors import UsageError
from rtde_spec.spec.importers import cb3_text, eseries_text, html_doc, markdown
from rtde_spec.spec.importers.cells import Lines, parse_name
from rtde_spec.spec.importers.model import Document
from rtde_spec.spec.importers.rows import field_rows, main_line
from rtde_spec.spec.schema import Spec

FORMATS = ("cb3-text", "e-series-text", "markdown", "html", "primary-text")
_DEFAULT_SOURCE = {
    "cb3-text": "cb3-guide",
    "e-series-text": "e-series-guide",
    "primary-text": "primary-guide",
}


def detect_format(text: str) -> str:
    """Which of UR's document forms this is, from its content alone."""
    head = text[:4096].lower()
    if "<table" in text.lower() or head.lstrip().startswith(("<!doctype html", "<html")):
        return "html"
    if "ROBOT_STATE_PACKAGE_TYPE" in text or "Sub Package of Robot State" in text:
        return "primary-text"
    if re.search(r"^\s*\|\s*Name\s*\|", text, re.MULTILINE):
        return "markdown"
    if re.search(r"^\s*Name\s*\|\s*$", text, re.MULTILINE):
        return "e-series-text"
    if re.search(r"^\s*Name\tType\t", text, re.MULTILINE):
        return "cb3-text"
    raise UsageError(
        "cannot tell the document's form: expected an RTDE guide (tab-separated text, "
        "pipe-terminated text, Markdown or HTML tables) or the primary interface document"
    )


def _slug(path: Path) -> str:
    return re.sub(r"[^a-z0-9]+", "-", path.stem.lower()).strip("-") or "document"


def read_document(
    path: Path | str, spec: Spec, source: str | None = None, line: str | None = None, fmt: str | None = None
) -> Document:
    """Read a document in any supported form into the common model."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        raise UsageError(f"no such document: {path}") from None
    except IsADirectoryError:
        raise UsageError(f"{path} is a directory, not a document") from None
    kind = fmt or detect_format(text)
    lines = Lines.of(spec)
    doc = Document(str(path), kind, source or _DEFAULT_SOURCE.get(kind) or _slug(path))
    if kind == "primary-text":
        from rtde_spec.spec.importers.primary_text import read_members

        doc.members = read_members(text, lines)
        doc.line = line or "e-series"
        return doc
    if kind == "cb3-text":
        tables = cb3_text.read_tables(text)
    elif kind == "e-series-text":

        def starts_row(name: str, type_: str) -> bool:
            word, _, _ = parse_name(name)
            return (
                bool(re.fullmatch(r"[A-Za-z_][A-Za-z0-9_{}]*", word))
                and type_.strip() != ""
                and (lines.type_name(type_) in lines.types.values())
            )

        tables = [eseries_text.split_rows(t, starts_row) for t in eseries_text.read_tables(text)]
    elif kind == "markdown":
        tables = markdown.read_tables(text)
    else:
        tables = html_doc.read_tables(text)
    doc.fields = field_rows(tables, lines)
    if not doc.fields:
        raise UsageError(f"{path}: no RTDE field table (Name, Type, Comment, Introduced in version) found")
    default = "cb3" if kind == "cb3-text" else "e-series"
    doc.line = line or main_line(doc.fields, default)
    return doc
