"""The floors diagram in docs/architecture.md, drawn from the package's imports.

`python -m tests.floors` rewrites the block between the markers; tests/test_structure.py
fails when the block differs from what the imports draw (a new arrow, a new room).
"""

from __future__ import annotations

import re
import sys

from tests.helpers import ROOT
from tests.test_structure import FLOORS, floor_of, import_graph

DOC = ROOT / "docs" / "architecture.md"
BEGIN, END = "<!-- floors: drawn by python -m tests.floors -->", "<!-- end floors -->"


def room(module: str) -> str:
    """A module's room in the picture: its top-level package (the generated constants apart)."""
    if module == "rtde_spec._generated.constants":
        return "_generated.constants"
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def diagram() -> str:
    graph = import_graph()
    rooms: dict[int, set[str]] = {}
    arrows: set[tuple[str, str, bool]] = set()
    for name, targets in graph.items():
        rooms.setdefault(floor_of(name), set()).add(room(name))
        for target in targets:
            a, b = room(name), room(target)
            if a != b:
                arrows.add((a, b, floor_of(target) > floor_of(name)))
    lines = ["```mermaid", "flowchart BT"]
    for index in range(len(FLOORS)):
        members = " & ".join(f'{r.replace(".", "_")}["{r}"]' for r in sorted(rooms.get(index, ())))
        lines.append(f'  subgraph floor{index}["floor {index}"]')
        lines.append(f"    {members}")
        lines.append("  end")
    for a, b, up in sorted(arrows):
        arrow = "-. lazy lookup up .->" if up else "-->"
        lines.append(f"  {a.replace('.', '_')} {arrow} {b.replace('.', '_')}")
    lines.append("```")
    return "\n".join(lines)


def block(text: str) -> str:
    match = re.search(re.escape(BEGIN) + r"\n(.*?)\n" + re.escape(END), text, re.S)
    return match.group(1) if match else ""


def main() -> int:
    text = DOC.read_text()
    if BEGIN not in text:
        print(f"{DOC}: no {BEGIN} marker", file=sys.stderr)
        return 1
    DOC.write_text(
        text.replace(block(text), diagram())
        if block(text)
        else text.replace(f"{BEGIN}\n{END}", f"{BEGIN}\n{diagram()}\n{END}")
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
