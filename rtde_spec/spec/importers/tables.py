"""Tables as every RTDE guide format reads into: a heading, header cells, rows with lines."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Table:
    """One table of a document, whatever its markup."""

    heading: str  # the nearest short line (or heading element) before it
    header: list[str]
    line: int
    rows: list[tuple[int, list[str]]] = field(default_factory=list)

    @property
    def is_field_table(self) -> bool:
        """Name | Type | Comment | Introduced in version — the guides' field tables."""
        head = [h.strip().lower() for h in self.header]
        return len(head) >= 3 and head[0] == "name" and head[1] == "type" and "comment" in head[2]

    @property
    def direction(self) -> str | None:
        text = self.heading.lower()
        if "input" in text and "output" not in text:
            return "input"
        if "output" in text and "input" not in text:
            return "output"
        return None


def is_heading(line: str) -> bool:
    """A short line of text: how the text exports show section titles."""
    text = line.strip()
    return 0 < len(text) <= 60 and not text.endswith(".")
