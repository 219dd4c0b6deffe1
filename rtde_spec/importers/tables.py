"""Tables as every RTDE guide format reads into: a heading, header cells, rows with lines."""

from __future__ import annotations

import re
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
    cut: bool = False  # the copy ends inside it: rows after the last one read are missing
    open_end: bool = False  # the text ends in it (nothing after its last row): cut unless that row is whole
    stub: tuple[int, str] | None = None  # (line, text) of a row the text stops in, too short to read
    stray: list[tuple[int, str]] = field(default_factory=list)  # (line, text) of cells no row starts

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


#: the marks a page break leaves in a text copy: "Page 7 of 9", "4/9", the page's address, the
#: browser's date line ("5/14/24, 10:15 AM"), a form feed
PAGE_MARK = re.compile(
    r"^\s*(?:\f|page\s+\d+(?:\s*(?:of|/)\s*\d+)?|\d+\s*/\s*\d+|https?://\S+"
    r"|\d{1,2}/\d{1,2}/\d{2,4},?\s+\d{1,2}:\d{2}(?:\s*[AP]M)?)\s*$",
    re.I,
)
FORM_FEED = "\f"  # pdftotext ends every page with one


def is_page_mark(text: str) -> bool:
    """A page number, a page's address or date line, or a form feed: never a cell. A browser's
    printed footer puts two on one line (`https://…/rtde-guide.html      1/9` in -layout)."""
    if FORM_FEED in text or PAGE_MARK.match(text):
        return True
    parts = re.split(r"\s{2,}", text.strip())
    return len(parts) > 1 and all(PAGE_MARK.match(part) for part in parts)


#: a page's footer or header holding a page mark beside its text: "Copyright © … A/S. Page 1 of 9",
#: "https://…/rtde-guide/ 1/9" (a browser's print), "5/14/24, 10:15 AM Real-Time Data Exchange …"
_MARK_AT_EDGE = re.compile(
    r"(?:^|\s)page\s+\d+(?:\s*(?:of|/)\s*\d+)?\s*$|(?:\s{2,}|://\S+\s+)\d+\s*/\s*\d+\s*$"
    r"|^\s*(?:page\s+\d+\s*(?:of|/)\s*\d+|https?://\S+|\d{1,2}/\d{1,2}/\d{2,4},?\s+\d{1,2}:\d{2}(?:\s*[AP]M)?)\s",
    re.I,
)


def is_page_line(text: str) -> bool:
    """A page mark, alone or at either end of a footer's or header's text: between tables (never a
    cell) it says a page broke there."""
    return is_page_mark(text) or bool(_MARK_AT_EDGE.search(text))


def split_form_feeds(text: str) -> list[tuple[int, str]]:
    """(line number, line) of a text, a form feed on a line of its own (pdftotext starts the next
    page's first line with it: "\fReal-Time Data Exchange (RTDE) Guide"). Lines are counted as an
    editor counts them (str.splitlines would end a line at the form feed, and count one more)."""
    out: list[tuple[int, str]] = []
    for number, raw in enumerate(text.split("\n"), start=1):
        parts = raw.rstrip("\r").split(FORM_FEED)
        for k, part in enumerate(parts):
            if k:
                out.append((number, FORM_FEED))
            if part.strip() or not k:
                out.append((number, part))
    return out


#: what a cell holds and a running header never does: a version, a snake_case name
_CELL_LIKE = re.compile(r"\d+\.\d+|^\S*_\S*$")


def running_lines(lines: list[str]) -> frozenset[str]:
    """The running header and footer of a paged copy: lines of words (a space in them, no version,
    no name) within two lines of a page break (a run of page marks), beside at least two breaks and
    half of them, or the document's first line (its title) beside one. Cells differ from page to
    page; a type or a version beside every break stays a cell."""
    texts = [t.strip() for t in lines]
    at = [i for i, t in enumerate(texts) if t]
    title = texts[at[0]] if at else ""
    seen: dict[str, int] = {}
    breaks = 0
    k = 0
    while k < len(at):
        if not is_page_line(lines[at[k]]):
            k += 1
            continue
        end = k
        while end + 1 < len(at) and is_page_line(lines[at[end + 1]]):
            end += 1
        breaks += 1
        for text in {texts[j] for j in at[max(0, k - 2) : k] + at[end + 1 : end + 3]}:
            seen[text] = seen.get(text, 0) + 1
        k = end + 1
    return frozenset(
        t
        for t, n in seen.items()
        if is_heading(t)
        and " " in t
        and not _CELL_LIKE.search(t)
        and ((n >= 2 and 2 * n >= breaks) or t == title)
    )


_DIRECTION_WORD = re.compile(r"\b(?:in|out)puts?\b", re.I)
#: a page number alone: between the rows of a text form (not a cell there) it is a page's footer
_PAGE_NUMBER = re.compile(r"\d{1,3}")


def continues(previous: Table, gap: list[str]) -> bool:
    """Whether a table after these lines is `previous` carried over a page: the lines hold a page
    mark and no heading of the guide's own kind (named as `previous`'s, the direction aside:
    "Robot Controller Outputs" after "Robot Controller Inputs" is the next section; a running header
    "RTDE Guide: inputs" is not), or a heading saying "(continued)"."""
    texts = [g.strip() for g in gap if g.strip()]
    if any("continued" in t.lower() and _same_kind(previous.heading, t) for t in texts):
        return True
    if not any(is_page_line(g) or _PAGE_NUMBER.fullmatch(g.strip()) for g in gap):
        return False
    return not any(is_heading(t) and _same_kind(previous.heading, t) and t != previous.heading for t in texts)


def _same_kind(a: str, b: str) -> bool:
    def shape(text: str) -> str:
        text = re.sub(r"\(continued\)", "", text, flags=re.I)
        return " ".join(_DIRECTION_WORD.sub("~", text).lower().split())

    return bool(a.strip()) and shape(a) == shape(b)


def is_heading(line: str) -> bool:
    """A short line of text: how the text exports show section titles."""
    text = line.strip()
    return 0 < len(text) <= 60 and not text.endswith(".")
