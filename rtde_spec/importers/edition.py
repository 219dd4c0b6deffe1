"""The edition a document says it is written for, read from its own words.

UR's documents name their software versions in their titles and notes: "Robot Software
5.9", "RealTime 5.10", "Client InterfacesV3.14andV5.9", "CB3 Software version: from 3.4
forward", "Valid for software versions: 10.12.0, 5.25.0 and later", "e-Series SW 5.25".
Each is a version the document knows of, so the newest one per product line is a lower
bound of its edition (with its version cells, the edition `--edition` can override).
A number is read as a version only after such a word, or as V5.9: "exceeds 1.0 V" is not.
"""

from __future__ import annotations

import re

from rtde_spec.importers.cells import Lines, full_version
from rtde_spec.metamodel.versions import Version

_V = r"\d+\.\d+(?:\.\d+)?"
#: a word that names software, then (within a few words) one or more versions
_NAMED = re.compile(
    rf"\b(?:software|sw|polyscope|realtime|real-time|release|versions?|e-series|cb3(?:\.1)?|ur-series)\b"
    rf"[^\n\d]{{0,40}}?({_V}(?:\s*(?:,|/|and|or|&)\s*{_V})*)",
    re.I,
)
_V_PREFIX = re.compile(rf"(?<![A-Z0-9])V({_V})(?![\d.])")  # V5.9, InterfacesV3.14andV5.9
#: text read for a title and notes: a document's versions are named near its top and in notes
_LIMIT = 2_000_000


def versions_named(text: str, lines: Lines) -> dict[str, str]:
    """Per product line, the newest version the text names as software (not in version cells)."""
    found: dict[str, Version] = {}
    body = text[:_LIMIT]
    named = [m.group(1) for m in _NAMED.finditer(body)] + [m.group(1) for m in _V_PREFIX.finditer(body)]
    for group in named:
        for raw in re.findall(_V, group):
            line = lines.line_of(raw)
            if line is None:
                continue
            version = Version.parse(full_version(raw))
            if line not in found or version > found[line]:
                found[line] = version
    return {line: str(v) for line, v in found.items()}


def newest(*versions: str | None) -> str | None:
    """The newest of some versions (None when there is none)."""
    present = [Version.parse(v) for v in versions if v]
    return str(max(present)) if present else None
