"""Compare the real-time interface's tables with spec/realtime/interface.yaml, edition by edition.

Each table is the whole message of one version: its rows are lined up with the fields the
spec sends at that version (the same order, the rows UR leaves unnamed against the spec's
reserved fields), so one inserted row is one change, not a shifted rest. Types, counts,
sizes, names and the TOTAL row's byte count are compared; a row the spec sends only from
a later version is an availability change; a table of a version no product line covers
(the workbook's "Pre-3.0") is reported as not compared.
"""

from __future__ import annotations

from difflib import SequenceMatcher

from rtde_spec.importers.changes import Change, mark_known
from rtde_spec.importers.model import DocRealtimeRow, DocRealtimeTable, Document
from rtde_spec.importers.realtime_tables import TYPES
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.realtime import PRIMITIVES, RealtimeField, RealtimeFile, layouts
from rtde_spec.metamodel.versions import Version

_UNNAMED = "(unnamed)"


def _reserved(fld: RealtimeField) -> bool:
    return fld.name.startswith("reserved") or "software only" in (fld.doc or "").lower()


def _token(row: DocRealtimeRow) -> str:
    return row.key or _UNNAMED


def _spec_token(fld: RealtimeField) -> str:
    return _UNNAMED if _reserved(fld) else fld.name


def type_text(type_: str, count: int) -> str:
    return f"{type_}[{count}]" if count > 1 else type_


def _row_type(row: DocRealtimeRow) -> str:
    return type_text(TYPES.get(row.type, row.type), row.count)


def _spec_type(fld: RealtimeField) -> str:
    return type_text(fld.type, fld.count or 1)


def plan_for(table: RealtimeFile, catalogue: Catalogue, line: str, edition: str) -> list[RealtimeField]:
    """The fields the spec says `edition` of `line` sends, in order."""
    version = Version.parse(edition)
    plans = [p for p in layouts(table, catalogue) if p.line == line and Version.parse(p.first) <= version]
    return list(plans[-1].fields) if plans else []


def _first_version(fld: RealtimeField, line: str, catalogue: Catalogue) -> str | None:
    info = catalogue.lines[line]
    if fld.since is None:
        return info.first_version
    if line in fld.since:
        return fld.since[line]
    return info.first_version if info.inherits is not None and info.inherits in fld.since else None


def _compare(row: DocRealtimeRow, fld: RealtimeField, where: str, doc: Document) -> list[Change]:
    out: list[Change] = []
    if _row_type(row) != _spec_type(fld):
        out.append(Change("changed", "type", fld.name, where, _spec_type(fld), _row_type(row), row.line))
    if row.key and row.key != fld.name:
        if _reserved(fld):
            # UR leaves these rows unnamed; in a rendered copy the paragraph before the row (a
            # link of the row above: "Safety Mode Types") reads as its name
            doc.remarks.append(
                f"line {row.line}: {row.name!r} stands where the spec has {fld.name} (unnamed)"
            )
        else:
            out.append(Change("changed", "name", fld.name, where, fld.name, row.key, row.line))
    return out


def _check_sizes(t: DocRealtimeTable, doc: Document) -> None:
    """A row whose bytes are not its values' size, or a TOTAL its rows do not add up to: remarks."""
    for row in [*t.header, *t.rows]:
        prim = PRIMITIVES.get(TYPES.get(row.type, row.type))
        if prim is not None and prim[1] * row.count != row.size:
            doc.remarks.append(
                f"line {row.line}: {row.name or _UNNAMED}: {row.count} x {row.type} is "
                f"{prim[1] * row.count} bytes, the table says {row.size}"
            )
    if t.total is not None:
        added = sum(r.size for r in [*t.header, *t.rows])
        if added != t.total[1]:
            doc.remarks.append(
                f"table {t.title!r}: its rows add up to {added} bytes, its TOTAL row says {t.total[1]}"
            )


def diff_table(t: DocRealtimeTable, doc: Document, spec: RealtimeFile, catalogue: Catalogue) -> list[Change]:
    """The differences of one edition's table from the message the spec gives that edition."""
    if t.edition is None or t.product_line is None:
        what = f"version {t.edition}" if t.edition else "no version of a product line"
        doc.remarks.append(f"table {t.title!r} ({what}): outside the spec's product lines, not compared")
        return []
    where = f"realtime {t.edition}"
    expected = plan_for(spec, catalogue, t.product_line, t.edition)
    _check_sizes(t, doc)
    if t.unread:
        doc.remarks.append(
            f"table {t.title!r}: "
            + ", ".join(f"line {n} ({what!r})" for n, what in t.unread[:5])
            + ": a row without its numbers (a workbook's formulas saved without their values: open "
            "and save it in Excel or LibreOffice); not read, so "
            + (
                "the message's length is not compared"
                if t.total is None
                else "fields it lacks are not reported"
            )
        )
    out: list[Change] = []
    for row in t.header:
        if TYPES.get(row.type, row.type) != spec.header[0].type:
            out.append(
                Change("changed", "type", spec.header[0].name, where, spec.header[0].type, row.type, row.line)
            )
    matcher = SequenceMatcher(
        None, [_token(r) for r in t.rows], [_spec_token(f) for f in expected], autojunk=False
    )
    by_name = {f.name: f for f in spec.fields}
    for op, a0, a1, b0, b1 in matcher.get_opcodes():
        rows, fields = t.rows[a0:a1], expected[b0:b1]
        paired = 0
        if op in ("equal", "replace"):
            pairs = list(zip(rows, fields, strict=False))
            for row, fld in pairs:
                out += [mark_known(c, fld.conflicts, doc.source) for c in _compare(row, fld, where, doc)]
            rows, fields = rows[len(pairs) :], fields[len(pairs) :]
            paired = len(pairs)
        # an added unnamed row is named by the spec field it follows, whose conflicts may record it
        before = expected[b0 + paired - 1] if b0 + paired > 0 else None
        for row in rows:
            later = by_name.get(row.key)
            if later is not None and later not in expected:
                first = _first_version(later, t.product_line, catalogue)
                change = Change(
                    "changed",
                    "availability",
                    later.name,
                    where,
                    {t.product_line: first},
                    {t.product_line: f"<= {t.edition}"},
                    row.line,
                )
                out.append(mark_known(change, later.conflicts, doc.source))
                continue
            if row.key or before is None:
                name = row.key or f"{_UNNAMED} line {row.line}"
            else:
                name = f"{_UNNAMED} after {before.name}"
            change = Change("added", "added", name, where, None, _row_type(row), row.line)
            out.append(mark_known(change, before.conflicts, doc.source) if before and not row.key else change)
        tail = op == "insert" or (op == "replace" and not rows)  # spec fields past the rows
        for fld in fields:
            if (
                t.skipped
                or [u for u in t.unread if u[1].upper() != "TOTAL"]
                or (tail and b1 == len(expected) and t.total is None)
            ):
                # a placeholder row, or rows end before the message does and no TOTAL row follows:
                # the table stops early (a copy cut short), which says nothing of these fields
                doc.unlisted.setdefault(where, []).append(fld.name)
                continue
            change = Change("removed", "removed", fld.name, where, _spec_type(fld), None, None)
            out.append(mark_known(change, fld.conflicts, doc.source))
    if where in doc.unlisted:
        why = (
            "a placeholder row stands for rows left out"
            if t.skipped
            else f"its rows stop at line {t.rows[-1].line if t.rows else t.line} before the message "
            "ends and no TOTAL row follows"
        )
        doc.remarks.append(
            f"table {t.title!r}: {why}; {len(doc.unlisted[where])} spec fields not listed are not "
            "reported as removed"
        )
    if t.total is not None and not t.skipped:
        size = 4 + sum(PRIMITIVES[f.type][1] * (f.count or 1) for f in expected)
        if size != t.total[1]:
            change = Change("changed", "length", "message", where, size, t.total[1], t.line)
            out.append(change)
    return out


def diff_realtime(doc: Document, spec: RealtimeFile, catalogue: Catalogue) -> list[Change]:
    """Every difference between the document's real-time tables and spec/realtime, known ones marked."""
    out: list[Change] = []
    for t in doc.realtime:
        out += diff_table(t, doc, spec, catalogue)
    return out
