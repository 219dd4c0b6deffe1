"""What a document can speak of: its product line and its edition.

A field introduced (on the document's line) after the document's edition is not one it
could list, so it is not "removed"; the edition is given (--edition) or is the newest
version the document's own version cells name.
"""

from __future__ import annotations

from rtde_spec.importers.model import Document
from rtde_spec.metamodel.schema import FieldSpec, Spec
from rtde_spec.metamodel.versions import Version

#: sources that are not documents a guide would be expected to repeat (urcl-ci: what UR's
#: client library's CI shows a URSim version has, spec/rtde/fields.yaml)
UNDOCUMENTED = {"third-party", "user", "urcl-ci"}


def first_on(since: dict[str, str] | None, line: str, spec: Spec) -> str | None:
    """The first version of `line` that has a field with this `since` (None: not on the line)."""
    lines = {p.id: p for p in spec.product_lines.product_lines}
    if since is None:
        return lines[line].first_version
    if line in since:
        return since[line]
    parent = lines[line].inherits
    return lines[line].first_version if parent is not None and parent in since else None


def first_versions(entry: FieldSpec, line: str, spec: Spec) -> list[str]:
    """The first version on `line` of each index range of a field (one for a plain field)."""
    if not entry.ranges:
        found = first_on(entry.since, line, spec)
        return [found] if found else []
    out = []
    for rng in entry.ranges:
        found = first_on(rng.since if rng.since is not None else entry.since, line, spec)
        if found:
            out.append(found)
    return out


def in_scope(entry: FieldSpec, doc: Document, spec: Spec) -> bool:
    """Whether the document should list this spec field: documented, on its line, not newer than it."""
    if entry.sources and set(entry.sources) <= UNDOCUMENTED:
        return False
    firsts = first_versions(entry, doc.line, spec)
    if not firsts:
        return False
    if doc.edition is None:
        return True
    edition = Version.parse(doc.edition)
    return any(Version.parse(v) <= edition for v in firsts)


def expected_names(spec: Spec, doc: Document, direction: str) -> list[str]:
    entries = spec.fields.inputs if direction == "input" else spec.fields.outputs
    return [e.name for e in entries if in_scope(e, doc, spec)]


def stops_early(doc: Document) -> set[str]:
    """Directions whose table has a placeholder row ("… and more") or is cut short (the copy
    ends inside it): it does not list them all."""
    return {t.direction for t in doc.tables if t.skipped or t.cut}


def directions(doc: Document) -> set[str]:
    """The directions the document has a field table for: it says nothing of the others."""
    return {t.direction for t in doc.tables} or {f.direction for f in doc.fields}
