"""URScript's lexer: the program text to tokens, each with its line, column and whether a line
break came before it (the parser lets a statement continue over a break only where it cannot end).

One pass over the text with one compiled pattern, so lexing is linear in the program's size.
Comments (`#` to the end of the line) are dropped wherever they stand; `$` starts a program label
(`$ 3 "MoveJ"`, the line markers PolyScope writes into every program it generates).
"""

from __future__ import annotations

import re
from typing import NamedTuple

from rtde_spec.emulator.urscript.nodes import ScriptFault

_PATTERN = re.compile(
    r"(?P<space>[ \t\r\f\v]+)|(?P<nl>\n)|(?P<comment>\#[^\n]*)"
    r"|(?P<num>\d+\.\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?|\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<str>\"(?:[^\"\\\n]|\\.)*\"|'(?:[^'\\\n]|\\.)*')"
    r"|(?P<name>[A-Za-z_]\w*)"
    r"|(?P<op>==|!=|<=|>=|[-+*/%()\[\],=:<>.$])"
)


class Token(NamedTuple):
    kind: str  # num, str, name, op, eof
    text: str
    line: int
    column: int  # 1-based
    nl: bool  # a line break between this token and the one before


def tokenize(text: str) -> list[Token]:
    """All tokens of `text`, ending with an `eof` token; a ScriptFault at a character no token starts."""
    tokens: list[Token] = []
    line, line_start, pos, nl = 1, 0, 0, False
    match = _PATTERN.match
    size = len(text)
    while pos < size:
        found = match(text, pos)
        if found is None:
            source = text[line_start : text.find("\n", pos) if "\n" in text[pos:] else size]
            raise ScriptFault(f"syntax_error_on_line:{line}:{source.strip()}", line, pos - line_start + 1)
        kind = found.lastgroup or "op"
        if kind == "nl":
            line, line_start, nl = line + 1, found.end(), True
        elif kind not in ("space", "comment"):
            tokens.append(Token(kind, found.group(), line, pos - line_start + 1, nl))
            nl = False
        pos = found.end()
    tokens.append(Token("eof", "", line, pos - line_start + 1, True))
    return tokens
