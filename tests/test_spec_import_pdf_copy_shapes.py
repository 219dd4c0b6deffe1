"""spec import on what a copy from a PDF viewer does to the text: ligatures, and the like.

A PDF's text layer gives "ﬁ", "ﬂ", "ﬀ" as one character each; copied (or run through pdftotext)
`configurable_digital_output` reads `conﬁgurable_digital_output`, and was taken for a field
`con` (every name with fi/fl/ff "removed").
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rtde_spec.metamodel.schema import Spec
from tests.test_spec_import_cut_pages import _fields
from tests.test_spec_import_realworld import ESERIES, _read, rows, seed, spec

__all__ = ["rows", "seed", "spec"]  # the module fixtures, shared

pytestmark = pytest.mark.skipif(not ESERIES.is_file(), reason="the shared seeds are not beside this checkout")

LIGATURES = {"ffi": "\ufb03", "ffl": "\ufb04", "ff": "\ufb00", "fi": "\ufb01", "fl": "\ufb02"}


def _ligatures(text: str) -> str:
    for letters, ligature in LIGATURES.items():
        text = text.replace(letters, ligature)
    return text


def test_ligatures_read_as_their_letters(tmp_path: Path, seed: str, spec: Spec) -> None:
    copy = _ligatures(seed)
    assert "conﬁgurable_digital_output" in copy and "tcp_oﬀset" in copy
    plain = _read(tmp_path, "plain.txt", seed, spec)
    doc = _read(tmp_path, "copied.txt", copy, spec)
    assert _fields(doc) == _fields(plain) and doc.problems == []
