"""Tables as every RTDE guide format reads into: a heading, header cells, rows with lines."""

from __future__ import annotations

from dataclasses import dataclass, field

from rtde_spec.errors import UsageError

#: a guide has a few hundred rows; more is not a guide, and is refused before it costs memory
MAX_ROWS = 20_000
#: bytes of a document read at most (UR's largest published pages are well under 2 MB)
MAX_BYTES = 16 * 1024 * 1024


def check_rows(count: int, line: int) -> None:
    """Refuse a document once it has more table rows than any guide has."""
    if count > MAX_ROWS:
        raise UsageError(
            f"more than {MAX_ROWS} table rows (at line {line}): not one of UR's interface documents"
        )


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
