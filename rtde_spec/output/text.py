"""Text for people: aligned tables and JSON, with nothing from the wire reaching the terminal raw."""

from __future__ import annotations

import json
import sys
from collections.abc import Sequence
from typing import Any

from rtde_spec.output.base import plain
from rtde_spec.printable import safe_text

__all__ = ["print_json", "safe_text", "table"]


def print_json(value: Any) -> None:
    json.dump(plain(value), sys.stdout, indent=2)
    sys.stdout.write("\n")


def table(headers: Sequence[str], rows: Sequence[Sequence[Any]], max_width: int = 60) -> str:
    """A plain aligned text table; long cells are cut with an ellipsis, controls escaped."""

    def cell(value: Any) -> str:
        text = safe_text("" if value is None else str(value))
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
