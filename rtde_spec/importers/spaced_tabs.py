"""A tab-separated copy whose tabs were turned into spaces: refused, never read.

An editor's "expand tabs" (tab stops every 4 or 8 columns) or "tab → 4 spaces", or a paste
through a form, leaves `Name    Type    Comment Introduced in version` over rows such as
`standard_digital_output UINT8   Standard digital outputs`: a cell can end in one space, like
a word of a comment, so where a comment stops and a version begins cannot be told. It looks
like pdftotext -layout's columns, but there the rows' cells line up under the header's; here
each row's type stands where its name happened to end.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from rtde_spec.errors import UsageError
from rtde_spec.importers.columns_text import HEAD

_ROW = re.compile(r"^[ \t]*[A-Za-z_][A-Za-z0-9_]*( +)(\S+)")
_SLACK = 4  # as columns_text: a cell a few characters from its column on another page still lines up
_LOOK = 400  # lines under a header looked at


def refuse_expanded_tabs(text: str, is_type: Callable[[str], bool], path: str) -> None:
    """Raise when a field table's rows do not line up under its header's Type column (most of
    them more than a few characters off): its tabs were expanded to spaces."""
    lines = text.split("\n")
    for at, line in enumerate(lines):
        head = HEAD.match(line)
        if head is None:
            continue
        column = head.start("type")
        off: list[tuple[int, int]] = []
        count = 0
        for number in range(at + 1, min(len(lines), at + _LOOK)):
            if HEAD.match(lines[number]):
                break
            row = _ROW.match(lines[number])
            if row is None or not is_type(row.group(2)):
                continue
            count += 1
            if abs(row.start(2) - column) > _SLACK:
                off.append((number + 1, row.start(2) + 1))
        if count >= 3 and 2 * len(off) > count:
            where = ", ".join(f"line {n} column {c}" for n, c in off[:3])
            raise UsageError(
                f"line {at + 1}: the field table's cells are apart by spaces that do not line up (the "
                f"header's Type at column {column + 1}, the rows' at {where}, …): the copy's tabs were "
                'turned into spaces (an editor\'s "expand tabs" or "tab → spaces"), and a cell that '
                "ends in one space cannot be told from a word of the comment; copy the page again "
                "keeping its tabs, or save it as HTML or Markdown, and import that",
                subject=f"file {path}",
            )
