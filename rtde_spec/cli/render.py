"""Output helpers shared by subcommands: tables, JSON-safe values, input bytes."""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rtde_spec.errors import RtdeSpecError

_HEX_RE = re.compile(r"^[0-9a-fA-F]*$")


def jsonable(value: Any) -> Any:
    """Values as JSON can hold them: bytes as hex, tuples as lists, enums as ints."""
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value).hex()
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return value
    return str(value)


def print_json(value: Any) -> None:
    json.dump(jsonable(value), sys.stdout, indent=2)
    sys.stdout.write("\n")


def table(headers: Sequence[str], rows: Sequence[Sequence[Any]], max_width: int = 60) -> str:
    """A plain aligned text table; long cells are cut with an ellipsis."""

    def cell(value: Any) -> str:
        text = "" if value is None else str(value)
        return text if len(text) <= max_width else text[: max_width - 1] + "…"

    cells = [[cell(v) for v in row] for row in rows]
    widths = [len(h) for h in headers]
    for row in cells:
        widths = [max(w, len(c)) for w, c in zip(widths, row, strict=True)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(headers, widths, strict=True)).rstrip()]
    lines.append("  ".join("-" * w for w in widths))
    for row in cells:
        lines.append("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip())
    return "\n".join(lines)


def parse_hex(text: str) -> bytes:
    """Hex with optional spaces, colons, newlines or a 0x prefix."""
    cleaned = re.sub(r"[\s:]", "", text)
    cleaned = cleaned[2:] if cleaned.lower().startswith("0x") else cleaned
    if not _HEX_RE.match(cleaned):
        bad = next(i for i, ch in enumerate(cleaned) if ch not in "0123456789abcdefABCDEF")
        raise RtdeSpecError(f"not hex: character {cleaned[bad]!r} at position {bad}")
    if len(cleaned) % 2:
        raise RtdeSpecError(f"not hex: odd number of digits ({len(cleaned)})")
    return bytes.fromhex(cleaned)


def read_input(arg: str) -> bytes:
    """HEX_OR_FILE: '-' is stdin, an existing path is read (hex text or binary), else hex."""
    if arg == "-":
        data = sys.stdin.buffer.read()
    elif Path(arg).is_file():
        data = Path(arg).read_bytes()
    else:
        try:
            return parse_hex(arg)
        except RtdeSpecError as exc:
            raise RtdeSpecError(f"{arg[:40]!r} is neither a file nor hex ({exc.reason})") from None
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        return data
    stripped = re.sub(r"[\s:]", "", text)
    if stripped and _HEX_RE.match(stripped) and len(stripped) % 2 == 0:
        return bytes.fromhex(stripped)
    return data
