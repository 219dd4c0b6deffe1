"""Compare an RTDE guide's field tables with spec/rtde/fields.yaml, field by field.

Availability is compared only for the product lines a row speaks of: the line the
document is written for (an empty "introduced in" cell there means "since the
line's first version"), the lines its versions name, and the lines inheriting
from those (PolyScope X from e-Series). A row naming only other lines' versions
says its own line does not have the field (the CB3 guide's ft_raw_wrench, 5.9.0).
"""

from __future__ import annotations

from collections import defaultdict

from rtde_spec.importers.cells import words
from rtde_spec.importers.changes import Availability, Change, mark_known, resolve
from rtde_spec.importers.model import DocField, Document, VersionNote
from rtde_spec.importers.scope import directions, in_scope, stops_early
from rtde_spec.metamodel.schema import FieldSpec, ProductLine, Spec
from rtde_spec.metamodel.versions import Version

_OTHER = {"input": "output", "output": "input"}


def _norm(avail: Availability) -> Availability:
    return {k: (str(Version.parse(v)) if v else None) for k, v in avail.items()}


def _notes_for(row: DocField, index: int | None) -> list[VersionNote]:
    return [n for n in row.notes if n.span is None or (index is not None and n.span[0] <= index <= n.span[1])]


def older_only(row: DocField, index: int | None, doc_line: str, lines: list[ProductLine]) -> bool:
    """A version cell naming only lines older than the document's ("3.3" read for e-Series): it says
    nothing of the document's own line, unlike a cell naming only a newer line (the CB3 guide's
    ft_raw_wrench, 5.9.0), which says the older line lacks the field."""
    named = {line for note in _notes_for(row, index) for line in note.versions}
    order = [p.id for p in lines]
    if not named or doc_line in named or doc_line not in order:
        return False
    return all(order.index(n) < order.index(doc_line) for n in named if n in order)


def covered_lines(row: DocField, index: int | None, doc_line: str, lines: list[ProductLine]) -> list[str]:
    """The lines a row speaks of for one index: the document's own and those its versions name."""
    named = {line for note in _notes_for(row, index) for line in note.versions}
    if not older_only(row, index, doc_line, lines):
        named.add(doc_line)
    for line in lines:
        if line.inherits in named:
            named.add(line.id)
    return [p.id for p in lines if p.id in named]


def doc_availability(row: DocField, index: int | None, doc_line: str, spec: Spec) -> Availability:
    lines = spec.product_lines.product_lines
    since: dict[str, str] = {}
    for note in _notes_for(row, index):
        since.update(note.versions)
    if not since:
        first = next(p.first_version for p in lines if p.id == doc_line)
        since = {doc_line: first}
    return _norm(resolve(since, lines, covered_lines(row, index, doc_line, lines)))


def spec_availability(entry: FieldSpec, index: int | None, covered: list[str], spec: Spec) -> Availability:
    rng = entry.range_for(index)
    since = rng.since if rng is not None and rng.since is not None else entry.since
    return _norm(resolve(since, spec.product_lines.product_lines, covered))


def _spec_text(entry: FieldSpec, spec: Spec) -> str:
    """Everything the spec says of a field in words: doc, unit, notes, and its enum's value names."""
    parts = [entry.doc, entry.unit, entry.deprecated, entry.reserved, entry.enum, entry.bits, entry.name]
    parts += [r.reserved for r in entry.ranges or []]
    parts += [f"{v.name} {v.doc or ''}" for e in spec.all_enums if e.name == entry.enum for v in e.values]
    return " ".join(p for p in parts if p)


def description_changed(doc_text: str, entry: FieldSpec, spec: Spec) -> bool:
    """A rewording keeps most words; a changed description loses them."""
    theirs = words(doc_text)
    if not theirs:
        return False
    text = _spec_text(entry, spec)
    ours = words(text.replace("_", " ")) | words(text)
    missing = theirs - ours
    return len(missing) >= 3 and len(missing) / len(theirs) > 0.5


def _availability_changes(row: DocField, entry: FieldSpec, doc: Document, spec: Spec) -> list[Change]:
    lines = spec.product_lines.product_lines
    if entry.index is None or row.index is None:
        indices: list[int | None] = (
            [None] if entry.index is None else list(range(entry.index[0], entry.index[1] + 1))
        )
    else:
        low, high = max(row.index[0], entry.index[0]), min(row.index[1], entry.index[1])
        indices = list(range(low, high + 1))
    out: list[Change] = []
    run: list[int | None] = []
    last: tuple[Availability, Availability] | None = None

    def flush() -> None:
        if last is not None and last[0] != last[1] and run and not row.notes:
            # a blank version cell is read as "since the line's first version"; where the spec says
            # otherwise the cell is reported, not taken as a change
            note = f"line {row.line}: {entry.name}: blank version cell (the spec has {last[0]})"
            if note not in doc.remarks:
                doc.remarks.append(note)
        elif last is not None and last[0] != last[1] and run:
            first, last_index = run[0], run[-1]
            span = None if first is None or last_index is None else (first, last_index)
            out.append(
                Change("changed", "availability", entry.name, row.direction, last[0], last[1], row.line, span)
            )

    for index in indices:
        if older_only(row, index, doc.line, lines):
            cell = row.version_text
            note = f"line {row.line}: {entry.name}: the version cell {cell!r} names only older lines"
            if note not in doc.remarks:
                doc.remarks.append(note)
        covered = covered_lines(row, index, doc.line, lines)
        pair = (spec_availability(entry, index, covered, spec), doc_availability(row, index, doc.line, spec))
        if pair != last or (index is not None and run and run[-1] is not None and index != run[-1] + 1):
            flush()
            run, last = [], pair
        run.append(index)
    flush()
    return out


def _compare(row: DocField, entry: FieldSpec, doc: Document, spec: Spec) -> list[Change]:
    out: list[Change] = []
    name, direction = entry.name, row.direction
    if row.type != entry.type:
        out.append(Change("changed", "type", name, direction, entry.type, row.type, row.line))
    if row.index is not None and entry.index is not None and tuple(row.index) != tuple(entry.index):
        out.append(Change("changed", "range", name, direction, list(entry.index), list(row.index), row.line))
    out += _availability_changes(row, entry, doc, spec)
    if description_changed(row.doc, entry, spec):
        out.append(Change("changed", "description", name, direction, entry.doc, row.doc, row.line))
    for change in out:
        change.extra["row"] = row
    return out


def _expected(entry: FieldSpec, doc: Document, spec: Spec) -> bool:
    """Whether the document should list a spec field: a documented field of its line and edition."""
    return in_scope(entry, doc, spec)


def diff_fields(doc: Document, spec: Spec) -> list[Change]:
    """Every difference between the document's field tables and the spec, known ones marked."""
    entries: dict[str, dict[str, FieldSpec]] = {
        "input": {e.name: e for e in spec.fields.inputs},
        "output": {e.name: e for e in spec.fields.outputs},
    }
    listed: dict[str, set[str]] = defaultdict(set)
    for row in doc.fields:
        listed[row.direction].add(row.name)
    changes: list[Change] = []
    for row in doc.fields:
        entry = entries[row.direction].get(row.name)
        if entry is not None:
            changes += [mark_known(c, entry.conflicts, doc.source) for c in _compare(row, entry, doc, spec)]
            continue
        other = entries[_OTHER[row.direction]].get(row.name)
        if other is not None and row.name not in listed[_OTHER[row.direction]]:
            change = Change(
                "changed",
                "direction",
                row.name,
                row.direction,
                other_dir(row.direction),
                row.direction,
                row.line,
            )
            change.extra["row"] = row
            changes.append(mark_known(change, other.conflicts, doc.source))
            continue
        change = Change("added", "added", row.name, row.direction, None, row.type, row.line, row.index)
        change.extra["row"] = row
        changes.append(change)
    partial = stops_early(doc)
    tabled = directions(doc)
    for direction, by_name in entries.items():
        if direction not in tabled:
            continue
        for name, entry in by_name.items():
            if name in listed[direction] or (
                name in listed[_OTHER[direction]] and name not in entries[_OTHER[direction]]
            ):
                continue
            if direction in partial and _expected(entry, doc, spec):
                doc.unlisted.setdefault(direction, []).append(name)  # not a removal: left out
                continue
            if _expected(entry, doc, spec):
                change = Change("removed", "removed", name, direction, entry.type, None, None, None)
                changes.append(mark_known(change, entry.conflicts, doc.source))
    return changes


def other_dir(direction: str) -> str:
    return _OTHER[direction]
