"""A difference between a document and the spec, in one shape for RTDE and primary fields."""

from __future__ import annotations

from dataclasses import dataclass
from dataclasses import field as dc_field
from typing import Any

from rtde_spec.metamodel.schema import Conflict, ProductLine

Availability = dict[str, str | None]  # product line -> first version, None: not on that line


@dataclass
class Change:
    """One reported difference: what it is, the spec's value, the document's value, and where."""

    kind: str  # added | removed | changed
    what: str  # added | removed | type | direction | availability | range | description
    field: str
    where: str  # RTDE: input | output; primary: family/member
    old: Any = None
    new: Any = None
    line: int | None = None
    index: tuple[int, int] | None = None
    known: Conflict | None = None
    extra: dict[str, Any] = dc_field(default_factory=dict)  # what --write needs (the document's row)

    @property
    def document_value(self) -> str | None:
        """The document's value as conflicts record it (`document:`)."""
        return value_text(self.what, self.new)

    def record(self) -> dict[str, Any]:
        out: dict[str, Any] = {"field": self.field, "where": self.where, "what": self.what}
        if self.index is not None:
            out["index"] = list(self.index)
        out["old"] = self.old
        out["new"] = self.new
        out["line"] = self.line
        if self.known is not None:
            out["known"] = {"decision": self.known.decision, "sources": list(self.known.sources)}
        decided = self.extra.get("decided")
        if self.known is None and decided is not None:
            out["decided_for"] = list(decided.sources)  # the value a conflict of that document records
        return out


def value_text(what: str, value: Any) -> str | None:
    """A value as one line of text: for tables, and to match a recorded conflict exactly."""
    if value is None:
        return None
    if what == "availability" and isinstance(value, dict):
        return ", ".join(f"{line} {ver or '-'}" for line, ver in value.items())
    if what == "range" and isinstance(value, (list, tuple)):
        return f"[{value[0]}, {value[1]}]"
    return str(value)


def matches(conflict: Conflict, change: Change) -> bool:
    """Whether a recorded conflict covers exactly this difference."""
    if conflict.what != change.what:
        return False
    if conflict.field is not None and conflict.field != change.field:
        return False
    if conflict.index is not None and tuple(conflict.index) != change.index:
        return False
    return conflict.document is None or conflict.document == change.document_value


def same_family(a: str, b: str) -> bool:
    """Document ids of one family: equal, or one an edition of the other (e-series-guide-5.9)."""
    return a == b or a.startswith(b + "-") or b.startswith(a + "-")


def mark_known(change: Change, conflicts: list[Conflict], source: str | None = None) -> Change:
    """Mark the change known when a conflict recorded for this document (family) covers it exactly:
    a conflict recorded because one document stops early never hides another's real change.

    A conflict of another document recording this very value is kept in `extra["decided"]`: still
    reported, never written (the same copy under another file name gets another source id)."""
    for conflict in conflicts:
        if source is not None and not any(same_family(s, source) for s in conflict.sources):
            if conflict.document is not None and matches(conflict, change):
                change.extra.setdefault("decided", conflict)
            continue
        if matches(conflict, change):
            change.known = conflict
            change.extra.pop("decided", None)
            break
    return change


def resolve(since: dict[str, str] | None, lines: list[ProductLine], covered: list[str]) -> Availability:
    """Per covered line the first version, by the spec's rules (omitted: every line; inherits)."""
    out: Availability = {}
    by_id = {p.id: p for p in lines}
    for line_id in covered:
        line = by_id[line_id]
        if since is None:
            out[line_id] = line.first_version
        elif line_id in since:
            out[line_id] = since[line_id]
        elif line.inherits is not None and line.inherits in since:
            out[line_id] = line.first_version
        else:
            out[line_id] = None
    return out
