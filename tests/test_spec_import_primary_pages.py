"""spec import on the primary interface document printed to pages and copied as text.

Each page ends in a footer with the page number ("Copyright © … A/S. Page 3 of 40", or a browser's
"https://… 3/40") and starts with the running title; between a row and the next table, the footer
was read as the row's description (requestedType "changed" to the copyright line, which --write
would have written into the spec).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.importers import read_document
from rtde_spec.importers.primary_diff import diff_primary
from rtde_spec.metamodel.loader import load_spec
from rtde_spec.metamodel.schema import Spec

ROOT = Path(__file__).resolve().parent.parent
PRIMARY = ROOT.parent / "shared" / "seeds" / "primary-secondary-interfaces.txt"
URL = "https://www.universal-robots.com/articles/ur/interface-communication/remote-control-via-tcpip/"

pytestmark = pytest.mark.skipif(not PRIMARY.is_file(), reason="the shared seeds are not beside this checkout")


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _paged(text: str, footer: str, title: str) -> str:
    """The text with a page break at every 120th line that is blank."""
    out: list[str] = []
    page = 0
    for k, line in enumerate(text.split("\n")):
        out.append(line)
        if k and k % 120 == 0 and not line:
            page += 1
            out += [footer.format(n=page), "", title, ""]
    return "\n".join(out)


def _members(path: Path, spec: Spec) -> list[tuple]:
    doc = read_document(path, spec)
    return [(m.title, [(f.name, f.type, f.doc, f.group) for f in m.fields]) for m in doc.members]


@pytest.mark.parametrize(
    ("footer", "title"),
    [
        (
            "Copyright © 2009–2024 by Universal Robots A/S. Page {n} of 40",
            "Primary and Secondary Client Interfaces",
        ),
        (URL + "   {n}/40", "11/27/24, 5:07 AM   Remote Control Via TCP/IP"),
    ],
)
def test_page_furniture_is_no_description(tmp_path: Path, spec: Spec, footer: str, title: str) -> None:
    text = PRIMARY.read_text(encoding="utf-8")
    paged = tmp_path / "primary.txt"
    paged.write_text(_paged(text, footer, title), encoding="utf-8")
    assert "Page 3 of 40" in paged.read_text(encoding="utf-8") or "3/40" in paged.read_text(encoding="utf-8")
    assert _members(paged, spec) == _members(PRIMARY, spec)
    assert [c for c in diff_primary(read_document(paged, spec), spec) if c.known is None] == []
