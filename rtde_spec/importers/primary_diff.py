"""Compare the primary interface document with spec/primary/interface.yaml, field by field.

Fields are matched by name once both are flattened to one spelling (camelCase and
snake_case agree), in order within a message; groups (repeated for each joint,
present only if ...) are part of a field's type as compared.
"""

from __future__ import annotations

from dataclasses import dataclass

from rtde_spec.importers.cells import words
from rtde_spec.importers.changes import Availability, Change, mark_known, resolve
from rtde_spec.importers.model import DocLayoutField, DocMember, Document
from rtde_spec.importers.primary_text import key
from rtde_spec.importers.scope import first_on as first_versions_of
from rtde_spec.metamodel.schema import FamilySpec, LayoutField, MemberSpec, Spec
from rtde_spec.metamodel.versions import Version


@dataclass
class _Leaf:
    path: str
    key: str
    type: str
    field: LayoutField


def type_text(fld: LayoutField) -> str:
    """A field's type as the document's rows can say it (double[6], string(uint8), bytes)."""
    kind = fld.kind
    if kind == "value":
        return f"{fld.type}[{fld.count}]" if fld.count else fld.type
    if kind == "string":
        return "string" if fld.length in (None, "rest") else f"string({fld.length})"
    if kind in ("bytes", "values"):
        return "bytes"
    return kind


def _leaves(fields: list[LayoutField], prefix: str = "", group: str = "") -> list[_Leaf]:
    out: list[_Leaf] = []
    for fld in fields:
        if fld.fields is not None:
            inner = f"repeat {fld.repeat}" if fld.repeat is not None else f"when {key(fld.when or '')}"
            out += _leaves(fld.fields, f"{prefix}{fld.name}.", inner)
            continue
        text = type_text(fld)
        out.append(_Leaf(prefix + fld.name, key(fld.name), f"{text} in {group}" if group else text, fld))
    return out


def _doc_type(row: DocLayoutField) -> str:
    return f"{row.type} in {row.group}" if row.group else row.type


def _norm(avail: Availability) -> Availability:
    return {k: (str(Version.parse(v)) if v else None) for k, v in avail.items()}


def _covered(named: dict[str, str], doc: Document, spec: Spec) -> list[str]:
    ids = {doc.line, *named}
    for line in spec.product_lines.product_lines:
        if line.inherits in ids:
            ids.add(line.id)
    return [p.id for p in spec.product_lines.product_lines if p.id in ids]


def _availability(
    named: dict[str, str], spec_since: dict[str, str] | None, doc: Document, spec: Spec
) -> tuple[Availability, Availability]:
    lines = spec.product_lines.product_lines
    covered = _covered(named, doc, spec)
    first = next(p.first_version for p in lines if p.id == doc.line)
    ours = _norm(resolve(spec_since, lines, covered))
    theirs = _norm(resolve(named or {doc.line: first}, lines, covered))
    return ours, theirs


def _first_on(since: dict[str, str] | None, doc: Document, spec: Spec) -> str | None:
    """The first version of the document's line that sends a field with this `since`."""
    return first_versions_of(since, doc.line, spec)


def _unversioned(
    named: dict[str, str], since: dict[str, str] | None, doc: Document, spec: Spec
) -> tuple[Availability, Availability] | None:
    """A row without a version (the docs site's listing, the workbook): it says only that the
    edition sends it. (spec, document) availability when the spec's first version is newer than
    the edition; None when they agree or the document names no edition."""
    if named or doc.edition is None or _before_line(doc, spec):
        return None
    first = _first_on(since, doc, spec)
    if first is not None and Version.parse(first) <= Version.parse(doc.edition):
        return None
    return {doc.line: first}, {doc.line: f"<= {doc.edition}"}


def _before_line(doc: Document, spec: Spec) -> bool:
    """An edition older than the spec's product line (CB3 3.2 where the line starts at 3.3.0):
    the spec says nothing of availability there; layouts are still compared."""
    line = next((p for p in spec.product_lines.product_lines if p.id == doc.line), None)
    if line is None or doc.edition is None:
        return False
    if Version.parse(doc.edition) >= Version.parse(line.first_version):
        return False
    note = (
        f"edition {doc.edition} is older than the spec's {doc.line} line (from {line.first_version}): "
        "availability not compared, layouts are"
    )
    if note not in doc.remarks:
        doc.remarks.append(note)
    return True


def _not_expected(since: dict[str, str] | None, doc: Document, spec: Spec) -> bool:
    """A spec field the document cannot list: not sent on its line at all (e-Series' trailing
    reserved byte in a CB3 listing), or first sent by a later version of its line. For an edition
    older than the line (the 3.2 listing, the line from 3.3.0) a field the line has from its
    first version is expected: the layouts are compared."""
    first = _first_on(since, doc, spec) if doc.line else None
    if doc.line and first is None:
        return True
    if doc.edition is None:
        return False
    line = next((p for p in spec.product_lines.product_lines if p.id == doc.line), None)
    if first is not None and line is not None and first == line.first_version and _before_line(doc, spec):
        return False
    return first is not None and Version.parse(first) > Version.parse(doc.edition)


def _layout(spec_member: MemberSpec, doc: Document) -> list[LayoutField]:
    """The spec's layout for the document's edition: an `older` one (python-urx's pre-3.0 layouts)
    when the edition precedes it, else the current one."""
    if doc.edition is None:
        return spec_member.fields
    edition = Version.parse(doc.edition)
    older = sorted(
        (o for o in spec_member.older if edition < Version.parse(o.before)),
        key=lambda o: Version.parse(o.before),
    )
    if not older:
        return spec_member.fields
    note = f"{spec_member.name}: compared with the spec's layout before {older[0].before} ({older[0].source})"
    if note not in doc.remarks:
        doc.remarks.append(note)
    return older[0].fields


def _group_only(row: DocLayoutField, leaf_type: str) -> bool:
    """A row whose block end the copy does not show, differing from the spec only in that group."""
    theirs = row.type
    ours = leaf_type.split(" in ")[0]
    return row.guessed and (ours == theirs or ours == f"{theirs}[6]")


def _find(spec: Spec, member: DocMember) -> tuple[FamilySpec, MemberSpec | None] | None:
    for fam in spec.primary.families:
        if fam.type == member.family_type:
            return fam, next((m for m in fam.members if m.type == member.member_type), None)
    return None


def _describe_changed(row: DocLayoutField, fld: LayoutField) -> bool:
    theirs = words(row.doc)
    ours = words(" ".join(p for p in (fld.doc, fld.enum, fld.name.replace("_", " "), fld.unit) if p))
    missing = theirs - ours
    return len(missing) >= 3 and len(missing) / len(theirs) > 0.5


def _member_changes(
    member: DocMember, fam: FamilySpec, spec_member: MemberSpec, doc: Document, spec: Spec
) -> list[Change]:
    where = f"{fam.name}/{spec_member.name}"
    out: list[Change] = []
    unversioned = _unversioned(member.versions, spec_member.since, doc, spec)
    if unversioned is not None or (not member.versions and (doc.edition is None or _before_line(doc, spec))):
        ours, theirs = unversioned or ({}, {})
    else:
        ours, theirs = _availability(member.versions, spec_member.since, doc, spec)
    if ours != theirs:
        out.append(
            mark_known(
                Change("changed", "availability", spec_member.name, where, ours, theirs, member.line),
                spec_member.conflicts,
                doc.source,
            )
        )
    leaves = _leaves(_layout(spec_member, doc))
    used: set[int] = set()
    for row in member.fields:
        match = next((i for i, leaf in enumerate(leaves) if i not in used and leaf.key == row.key), None)
        if match is None:
            change = Change("added", "added", row.name, where, None, _doc_type(row), row.line)
            change.extra["row"] = row
            out.append(mark_known(change, spec_member.conflicts, doc.source))
            continue
        used.add(match)
        leaf = leaves[match]
        found: list[Change] = []
        alone = row.block and sum(r.block == row.block for r in member.fields) == 1
        if alone and leaf.type == f"{row.type}[{row.group.split()[-1]}]":
            pass  # "for each joint: double DHa" alone in its block is the spec's double[6]
        elif not row.group and " in repeat " in leaf.type and leaf.type.split(" in ")[0] == row.type:
            note = f"line {row.line}: {where} {row.name}: listed once, without the spec's group ({leaf.type})"
            doc.remarks.append(note)  # an edition with no "repeated for each joint" line
        elif leaf.type != _doc_type(row) and row.type and _group_only(row, leaf.type):
            note = (
                f"line {row.line}: {where} {row.name}: {_doc_type(row)} read in a block whose end "
                f"is a guess (the spec: {leaf.type}), not a change"
            )
            doc.remarks.append(note)
        elif leaf.type != _doc_type(row) and row.type:
            found.append(Change("changed", "type", leaf.path, where, leaf.type, _doc_type(row), row.line))
        since = leaf.field.since or spec_member.since
        named = row.versions or member.versions
        unversioned = _unversioned(named, since, doc, spec)
        if unversioned is not None or (not named and (doc.edition is None or _before_line(doc, spec))):
            ours, theirs = unversioned or ({}, {})
        else:
            ours, theirs = _availability(named, since, doc, spec)
        if ours != theirs:
            found.append(Change("changed", "availability", leaf.path, where, ours, theirs, row.line))
        if row.doc and _describe_changed(row, leaf.field):
            found.append(
                Change("changed", "description", leaf.path, where, leaf.field.doc, row.doc, row.line)
            )
        for change in found:
            change.extra["row"] = row
            out.append(mark_known(change, leaf.field.conflicts, doc.source))
    last = max(used, default=-1)
    for i, leaf in enumerate(leaves):
        if member.cut and i > last and i not in used:
            doc.remarks.append(f"{where} {leaf.path}: after where the copy is cut short, not compared")
            continue
        if i not in used and not _not_expected(leaf.field.since or spec_member.since, doc, spec):
            out.append(
                mark_known(
                    Change("removed", "removed", leaf.path, where, leaf.type, None, None),
                    leaf.field.conflicts,
                    doc.source,
                )
            )
    return out


def diff_primary(doc: Document, spec: Spec) -> list[Change]:
    """Every difference between the document's message tables and spec/primary, known ones marked."""
    out: list[Change] = []
    for member in doc.members:
        doc.remarks += [n for n in member.notes if n not in doc.remarks]
        found = _find(spec, member)
        if found is None or found[1] is None:
            family = found[0].name if found else f"type {member.family_type}"
            change = Change(
                "added", "added", member.title, family, None, f"sub-type {member.member_type}", member.line
            )
            change.extra["member"] = member
            out.append(mark_known(change, found[0].conflicts if found else [], doc.source))
            continue
        if not member.fields and found[1].fields:
            # "This package contains a checksum ...": the listing describes it in words only
            doc.remarks.append(
                f"line {member.line}: {found[0].name}/{found[1].name}: listed without fields, not compared"
            )
            continue
        out += _member_changes(member, found[0], found[1], doc, spec)
    return out
