"""spec import on tab copies broken by pages whose footer or header holds text beside the page mark.

A print of the guide (from a browser, or UR's PDF) puts "Copyright © … A/S. Page 1 of 9" or the
page's address and "1/9" on one line, then the running title and the table's header again. Copied
as text (tabs between cells), the rows after it are the same table: read as the plain copy is,
never as a table of no direction (every field after the break "removed").
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_cut_pages import HEADER, _fields, rendered
from tests.test_spec_import_realworld import ESERIES, _read, rows, seed, spec

__all__ = ["rows", "seed", "spec"]  # the module fixtures, shared

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")

TITLE = "Real-Time Data Exchange (RTDE) Guide"
URL = (
    "https://www.universal-robots.com/articles/ur/interface-communication/real-time-data-exchange-rtde-guide/"
)
TAB_HEADER = "\t".join(HEADER)
BEFORE = ("tool_mode", "actual_joint_voltage", "input_int_register_X")


def tabbed(rows: dict[str, list[list[str]]], page: object = None) -> str:
    """The page copied as tab-separated text; `page(n)` gives the lines a page break puts before
    the rows named in BEFORE."""
    lines = [TITLE]
    for direction, heading in (("input", "Robot Controller Inputs"), ("output", "Robot Controller Outputs")):
        lines += [heading, TAB_HEADER]
        for cells in rows[direction]:
            if page is not None and cells[0] in BEFORE:
                lines += page(BEFORE.index(cells[0]) + 1)  # type: ignore[operator]
            lines.append("\t".join(cells))
    return "\n".join(lines) + "\n"


FOOTERS = {
    "copyright and page": lambda n: [f"Copyright © 2009–2024 by Universal Robots A/S. Page {n} of 9", TITLE],
    "copyright, tab, page": lambda n: [
        f"Copyright © 2009–2024 by Universal Robots A/S.\tPage {n} of 9",
        TITLE,
    ],
    "address and page": lambda n: [f"{URL}   {n}/9", f"11/27/24, 5:07 AM   {TITLE}"],
    "address, tab, page": lambda n: [f"{URL}\t{n}/9", f"11/27/24, 5:07 AM\t{TITLE}"],
    "title and page": lambda n: [f"{TITLE} Page {n} of 9"],
    "bare page number": lambda n: [str(n), TITLE],
    "copyright and number": lambda n: [f"Copyright © 2009–2024 by Universal Robots A/S. {n}"],
    "form feed, tab date": lambda n: [f"Page {n} of 9", "\f", f"27/11/2024, 17:07\t{TITLE}"],
}


@pytest.mark.parametrize("footer", sorted(FOOTERS))
def test_tab_copy_with_a_footer_reads_as_the_plain_copy(
    tmp_path: Path, rows: dict, spec: Spec, footer: str
) -> None:
    plain = _read(tmp_path, "plain.txt", tabbed(rows), spec)
    doc = _read(tmp_path, "paged.txt", tabbed(rows, lambda n: [*FOOTERS[footer](n), TAB_HEADER]), spec)
    assert _fields(doc) == _fields(plain)
    assert [(t.direction, t.fields) for t in doc.tables] == [(t.direction, t.fields) for t in plain.tables]
    assert doc.problems == []


def test_tab_copy_without_the_header_repeated(tmp_path: Path, rows: dict, spec: Spec) -> None:
    """The footer's page mark alone says the page broke (the header is not printed again)."""
    plain = _read(tmp_path, "plain.txt", tabbed(rows), spec)
    doc = _read(tmp_path, "paged.txt", tabbed(rows, FOOTERS["copyright and page"]), spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []


def test_a_heading_of_the_other_direction_still_starts_a_table(
    tmp_path: Path, rows: dict, spec: Spec
) -> None:
    """The header repeated under a heading naming a direction is the next section, not a page."""
    doc = _read(tmp_path, "plain.txt", tabbed(rows), spec)
    assert [t.direction for t in doc.tables] == ["input", "output"]


@pytest.mark.parametrize(
    "footer", ["Copyright © 2009–2024 by Universal Robots A/S. Page 7 of 9", f"{URL}   7/9"]
)
def test_rendered_copy_with_a_footer_reads_as_the_plain_copy(
    tmp_path: Path, rows: dict, spec: Spec, footer: str
) -> None:
    plain = _read(tmp_path, "plain.txt", rendered(rows), spec)
    doc = _read(tmp_path, "paged.txt", rendered(rows, "tool_mode", (footer, TITLE, *HEADER)), spec)
    assert _fields(doc) == _fields(plain)
    assert doc.problems == []


@pytest.mark.parametrize("header", [False, True])
def test_pipe_copy_with_a_bare_page_number(tmp_path: Path, seed: str, spec: Spec, header: bool) -> None:
    """The seed's `|` form with a page's number alone and the running title between two rows:
    the rows after it were dropped unsaid (82 fields "removed")."""
    repeated = "Name |\nType |\nComment |\nIntroduced in Version |\n|---|---|---|---|\n" if header else ""
    paged = seed.replace("\nactual_q |\n", f"\n4\n{TITLE}\n{repeated}actual_q |\n", 1)
    assert paged != seed
    plain = _read(tmp_path, "plain.txt", seed, spec)
    doc = _read(tmp_path, "paged.txt", paged, spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []


def test_another_tables_header_after_a_page_break_starts_that_table(tmp_path: Path, spec: Spec) -> None:
    """The CB3 guide copied without its `----` rulers, a page's number before "Data types": the
    outputs table went on over the break, and "Name Type Size in bits", "BOOL …" became fields."""
    text = (ESERIES.parent / "rtde-guide-cb3-era.txt").read_text(encoding="utf-8")
    plain = _read(tmp_path, "plain.txt", text, spec)
    at = text.index("\nData types\n")
    paged = re.sub(r"(?m)^-+\t-+\t-+\t-+\n", "", text[:at] + "\nPage 5 of 9\n" + text[at:])
    doc = _read(tmp_path, "paged.txt", paged, spec)
    assert _fields(doc) == _fields(plain)
