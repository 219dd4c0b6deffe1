"""Per-index availability of a register family, and back to `since` / `ranges` entries.

Writing an import that moves one range's version (or widens the family) is done on
the expanded form: every index gets its since map and reserved note, the change is
applied to the indices it names, and contiguous runs become `ranges` again.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rtde_spec.metamodel.schema import ProductLine

Since = dict[str, str] | None


def all_lines(lines: list[ProductLine]) -> dict[str, str]:
    """`since` omitted, written out: every line that does not inherit, from its first version."""
    return {p.id: p.first_version for p in lines if p.inherits is None}


def apply(since: Mapping[str, str] | None, new: Mapping[str, str | None], lines: list[ProductLine]) -> Since:
    """A since map with the document's versions for the lines it speaks of (None: not there)."""
    out = dict(since) if since is not None else all_lines(lines)
    by_id = {p.id: p for p in lines}
    for line_id, version in new.items():
        line = by_id[line_id]
        if version is None:
            out.pop(line_id, None)
            continue
        implicit = line.inherits is not None and line.inherits in out and version == line.first_version
        if implicit:
            out.pop(line_id, None)
        else:
            out[line_id] = version
    # an inheriting line whose parent went away keeps nothing implicit
    order = [p.id for p in lines]
    out = {k: out[k] for k in order if k in out}
    return None if out == all_lines(lines) else out


def expand(entry: Any) -> dict[int, tuple[Since, str | None]]:
    """index -> (since, reserved) of a family entry as YAML data."""
    low, high = entry["index"]
    out: dict[int, tuple[Since, str | None]] = {}
    for i in range(low, high + 1):
        since, reserved = entry.get("since"), entry.get("reserved")
        for rng in entry.get("ranges") or []:
            if rng["index"][0] <= i <= rng["index"][1]:
                since = rng.get("since", since)
                reserved = rng.get("reserved", reserved)
        out[i] = (dict(since) if since is not None else None, reserved)
    return out


def runs(per_index: Mapping[int, tuple[Since, str | None]]) -> list[tuple[int, int, Since, str | None]]:
    """Contiguous indices with the same since and reserved note."""
    out: list[tuple[int, int, Since, str | None]] = []
    for i in sorted(per_index):
        since, reserved = per_index[i]
        if out and out[-1][1] == i - 1 and out[-1][2] == since and out[-1][3] == reserved:
            low, _, s, r = out[-1]
            out[-1] = (low, i, s, r)
        else:
            out.append((i, i, since, reserved))
    return out
