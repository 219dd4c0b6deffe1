"""Hex as people copy it: dumps with offsets (Wireshark, tshark -x, xxd, hexdump -C), C arrays
(`0x00, 0x05`) and escaped strings (`\\x00\\x05`).

Each dump line is an offset, the bytes in hex and, often, the same bytes as ASCII, which may
itself look like hex ("ab"). So a line holds as many bytes as the next line's offset says,
and the last line the hex groups before a column as long as the bytes they make. Each offset
must continue the one before (a line missing or pasted twice is named, not decoded into wrong
packages); hexdump's `*` (lines like the one above, left out) is filled in from the next offset.
"""

from __future__ import annotations

import re

from rtde_spec.errors import RtdeSpecError

# an offset: then a colon (xxd) or 2+ spaces (Wireshark 3, tshark -x and hexdump -C 2): plain
# hex split by single spaces is not a dump; hexdump -C ends with a line of the offset alone
_OFFSET = re.compile(r"^\s*([0-9a-fA-F]{4,8})(?::\s*|\s{2,}|\s*$)")
_GROUP = re.compile(r"^(?:[0-9a-fA-F]{2}){1,4}$")  # a byte, or xxd's groups of 2 or 4
_ARRAY = re.compile(r"^\s*(?:0[xX][0-9a-fA-F]{1,2}\s*(?:,\s*|\s+|$))+$")
_ESCAPED = re.compile(r"^\s*(?:\\x[0-9a-fA-F]{2})+\s*$")


def looks_like_hex_forms(head: bytes) -> bool:
    """Whether the start of a file is printable text whose first line is a dump line, a C array
    or an escaped string (such a file is read whole as text, not streamed as bytes)."""
    try:
        text = head[:4096].decode("ascii")
    except UnicodeDecodeError:
        return False
    if not all(c.isprintable() or c in "\t\r\n" for c in text):
        return False
    first = next((line for line in text.splitlines() if line.strip()), "")
    start = first.strip()
    return bool(_OFFSET.match(first)) or start.startswith(("0x", "0X", "\\x"))


def from_hex_forms(text: str) -> bytes | None:
    """The bytes of a dump, a C array or an escaped string; None when `text` is none of them."""
    if _ARRAY.match(text):
        return bytes(int(token, 16) for token in re.findall(r"0[xX]([0-9a-fA-F]{1,2})", text))
    if _ESCAPED.match(text):
        return bytes.fromhex(text.strip().replace("\\x", ""))
    lines = [(n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip()]
    found = [_OFFSET.match(line) for _, line in lines if line.strip() != "*"]
    if not found or not all(found) or not any(m.end() < len(m.string.rstrip()) for m in found if m):
        return None  # (hex alone, "00045601", is a package, not an offset with no bytes)
    if len(found) == 1 and found[0] and int(found[0].group(1), 16):
        return None  # one line is a dump only from offset 0: "0004  5601" is plain hex
    return _dump(lines)


def _dump(lines: list[tuple[int, str]]) -> bytes:
    out = bytearray()
    start: int | None = None
    last = b""  # the line above, for hexdump's `*`
    starred = False
    for i, (number, line) in enumerate(lines):
        if line.strip() == "*":
            starred = True
            continue
        found = _OFFSET.match(line)
        assert found is not None
        offset = int(found.group(1), 16)
        start = offset if start is None else start
        at = start + len(out)
        if starred and offset > at and last and (offset - at) % len(last) == 0:
            out += last * ((offset - at) // len(last))
            at = offset
        starred = False
        if offset != at:
            raise RtdeSpecError(
                f"hex dump line {number}: offset {offset:#x} where {at:#x} was due "
                "(a line missing or given twice?)"
            )
        following = lines[i + 1][1] if i + 1 < len(lines) else "*"  # its offset bounds this line
        ahead = _OFFSET.match(following) if following.strip() != "*" else None
        step = int(ahead.group(1), 16) - offset if ahead is not None else 0
        wanted = step if step > 0 else None  # (an offset going back is said at its own line)
        last = _line_bytes(line[found.end() :], wanted, number)
        out += last
    return bytes(out)


def _line_bytes(rest: str, wanted: int | None, number: int) -> bytes:
    """One line's bytes after its offset: `wanted` of them where the next offset says, else the
    hex groups before an ASCII column as long as they are (hexdump -C's is between bars)."""
    tokens = list(re.finditer(r"\S+", rest))
    groups: list[str] = []
    for token in tokens:
        if not _GROUP.match(token.group()):
            break
        groups.append(token.group())
    if wanted is not None:
        data = bytes.fromhex("".join(groups))[:wanted]
        if len(data) != wanted:
            raise RtdeSpecError(
                f"hex dump line {number}: {len(data)} bytes, but the next line's offset is {wanted} bytes "
                "on (a line missing, or this one cut?)"
            )
        return data
    for count in range(len(groups), -1, -1):
        data = bytes.fromhex("".join(groups[:count]))
        column = rest[tokens[count - 1].end() :] if count else rest
        shown = column.strip()
        if not shown or (shown.startswith("|") and shown.endswith("|")) or len(column.lstrip()) == len(data):
            return data
    raise RtdeSpecError(f"hex dump line {number}: cannot tell its hex bytes from its text")
