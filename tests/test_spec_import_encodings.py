"""spec import on the primary interface document saved in an 8-bit code page.

The document marks a group's rows with "→" (`→ double q_actual`); Windows-1252 and Latin-1 have no
arrow, so a save in them writes "?", and UTF-8 read back as Windows-1252 gives "â†’". Such a
copy must read as the UTF-8 one, saying what it took as the arrow, never as fields removed.
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

pytestmark = pytest.mark.skipif(not PRIMARY.is_file(), reason="the shared seeds are not beside this checkout")


@pytest.fixture(scope="module")
def spec() -> Spec:
    return load_spec(ROOT / "spec")


def _members(path: Path, spec: Spec) -> list[tuple]:
    doc = read_document(path, spec)
    return [
        (m.title, m.member_type, [(f.name, f.type, f.group, f.block) for f in m.fields]) for m in doc.members
    ]


SAVES = {
    "cp1252": lambda t: t.encode("cp1252", errors="replace"),
    "latin-1": lambda t: t.encode("latin-1", errors="replace"),
    "utf-8 read as cp1252": lambda t: t.encode("utf-8").decode("cp1252", errors="replace").encode("utf-8"),
    "typed arrow": lambda t: t.replace("→", "->").encode("utf-8"),
}


@pytest.mark.parametrize("save", sorted(SAVES))
def test_an_8_bit_copy_reads_as_the_utf8_one(tmp_path: Path, spec: Spec, save: str) -> None:
    text = PRIMARY.read_text(encoding="utf-8")
    copy = tmp_path / "primary.txt"
    copy.write_bytes(SAVES[save](text))
    assert "→" not in copy.read_text(encoding="utf-8", errors="replace")
    assert _members(copy, spec) == _members(PRIMARY, spec)
    doc = read_document(copy, spec)
    assert [c for c in diff_primary(doc, spec) if c.known is None] == []
    first = text[: text.index("→ double q_actual")].count("\n") + 1
    assert any(r.startswith(f"lines {first},") and "'→'" in r for r in doc.remarks), doc.remarks
