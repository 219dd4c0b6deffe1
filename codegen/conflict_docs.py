"""The differences between UR's documents and the spec that were decided on purpose, as a doc section.

They live in spec/ as `conflicts:` (what `spec import` then stops reporting); a reader of
the reference should see them too, with the decision and its sources, not only a
maintainer running `spec import --show-known`.
"""

from __future__ import annotations

from collections.abc import Iterable

from rtde_spec.metamodel.schema import Conflict

from .render import md_table

HEADERS = ["Where", "What differs", "The document says", "Sources", "Decision"]


def conflict_rows(where: str, conflicts: Iterable[Conflict]) -> list[list[object]]:
    """One row per recorded conflict of one field, member or register range."""
    rows: list[list[object]] = []
    for c in conflicts:
        place = f"`{where}`"
        if c.index is not None:
            place += f" [{c.index[0]}..{c.index[1]}]"
        if c.field:
            place += f" (the document's `{c.field}`)"
        rows.append([place, c.what, c.document or "", ", ".join(c.sources), c.decision])
    return rows


def conflicts_section(rows: list[list[object]]) -> str:
    """The section, or nothing when no difference is recorded."""
    if not rows:
        return ""
    return (
        "\n## Where the documents differ\n\n"
        "Differences between a published document and this spec that were decided on purpose "
        "(recorded as `conflicts:` in spec/; `rtde-spec spec import DOCUMENT --show-known` "
        "lists them beside a re-import):\n\n" + md_table(HEADERS, rows)
    )
