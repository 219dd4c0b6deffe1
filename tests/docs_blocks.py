"""The fenced code blocks of README.md and docs/*.md, with the directives that say how to run them.

A directive is an HTML comment on the line before a fence, invisible on the rendered
page: `<!-- test: file=NAME -->` writes the block to NAME in the workspace (a scenario,
a recipe, a script the next block uses); `<!-- test: until-stopped=S -->` marks commands
that run until Ctrl-C (`serve`, `watch`): each must still be running after S seconds;
`<!-- test: own-emulator -->` runs the block with the test's emulator stopped (it starts
its own); `<!-- test: exit=N -->` expects each command to exit N (an example of an
error); `<!-- test: prints=TEXT -->` expects a python block to print TEXT (`+` for a
space). Every block has a language: python and sh run, yaml/xml/json are parsed, text
is output shown to the reader and is not run.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LANGUAGES = {"python", "sh", "yaml", "xml", "json", "text", "mermaid"}
_FENCE = re.compile(r"^```(\S*)\s*$")
_DIRECTIVE = re.compile(r"^<!-- test: (.*) -->\s*$")


@dataclass
class Block:
    doc: str
    line: int
    language: str
    text: str
    directives: dict[str, str] = field(default_factory=dict)

    @property
    def id(self) -> str:
        return f"{self.doc}:{self.line}"


def documents() -> list[Path]:
    """README.md and the hand-written docs (docs/reference/ is generated tables, no code)."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def blocks(path: Path) -> list[Block]:
    lines = path.read_text(encoding="utf-8").splitlines()
    out: list[Block] = []
    i = 0
    name = str(path.relative_to(ROOT))
    while i < len(lines):
        fence = _FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        directives: dict[str, str] = {}
        if i > 0 and (d := _DIRECTIVE.match(lines[i - 1])):
            for item in d.group(1).split():
                key, _, value = item.partition("=")
                directives[key] = value
        start = i
        i += 1
        body: list[str] = []
        while i < len(lines) and not lines[i].startswith("```"):
            body.append(lines[i])
            i += 1
        out.append(Block(name, start + 1, fence.group(1), "\n".join(body) + "\n", directives))
        i += 1
    return out


def commands(block: Block) -> list[str]:
    """The sh block's commands: one per line, comments and blank lines dropped, `\\` joined."""
    out: list[str] = []
    pending = ""
    for raw in block.text.splitlines():
        line = raw.rstrip()
        if line.endswith("\\"):
            pending += line[:-1] + " "
            continue
        line = pending + line
        pending = ""
        if line.strip() and not line.lstrip().startswith("#"):
            out.append(line.strip())
    return out
