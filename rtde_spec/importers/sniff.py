"""What a document's bytes are before any reader sees them: the files people have of UR's documents
include the PDFs themselves, an Excel 97-2003 copy and a workbook saved under another name; each
is said by name (with what to do) instead of "cannot tell the document's form"."""

from __future__ import annotations

from pathlib import Path

from rtde_spec.errors import UsageError

#: a workbook is a ZIP archive (its name may be Client_Interface.xls, or .xlsx.download)
ZIP = b"PK\x03\x04"
_OLE2 = bytes.fromhex("D0CF11E0A1B11AE1")


def refuse_binary(data: bytes, path: Path) -> None:
    """Raise for a PDF, an OLE2 (.xls/.doc) file or other binary data, naming the file and what to do."""
    head = data[:1024]
    if head.lstrip().startswith(b"%PDF-"):
        raise UsageError(
            f"{path}: a PDF; import its text: `pdftotext {path.name} out.txt` (plain or -layout)"
        )
    if head.startswith(_OLE2):
        raise UsageError(
            f"{path}: an Excel 97-2003 (.xls) or Word (.doc) file, which is not read; save it as .xlsx "
            "(File > Save As in Excel or LibreOffice) and import that"
        )
    if head.startswith(ZIP):
        raise UsageError(
            f"{path}: a ZIP archive (a .docx, .odt or a zipped folder?); give the document as text, "
            "Markdown, HTML or the .xlsx workbook (--form xlsx reads a workbook under any name)"
        )


def utf16_without_bom(data: bytes) -> str | None:
    """The codec of UTF-16 text written without a byte-order mark (NUL in every other byte of the
    ASCII text), else None: read as UTF-8 it is NUL-spaced letters no reader finds a table in."""
    sample = data[:4096]
    if len(sample) < 4 or b"\0" not in sample:
        return None
    odd, even = sample[1::2], sample[0::2]
    if odd.count(0) > 0.9 * len(odd) and even.count(0) < 0.1 * len(even):
        return "utf-16-le"
    if even.count(0) > 0.9 * len(even) and odd.count(0) < 0.1 * len(odd):
        return "utf-16-be"
    return None
