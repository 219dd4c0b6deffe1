"""The parser's reading position in a program's tokens, and the syntax errors it reports from there.

Both halves of the parser (statements in parser.py, expressions in expression_parser.py) read
through this: one token at a time, never backwards, so parsing is linear in the program. A
syntax error names the line as the controller does (`syntax_error_on_line:LINE:SOURCE`); a
token missing at the end of a line is reported on that line, not the next one.
"""

from __future__ import annotations

from rtde_spec.emulator.urscript.lexer import Token, tokenize
from rtde_spec.emulator.urscript.nodes import ScriptFault

MAX_NESTING = 100  # brackets, operators and blocks inside one another
KEYWORDS = {
    "and", "or", "xor", "not", "if", "elif", "else", "while", "end", "return", "break",
    "continue", "def", "sec", "thread", "run", "kill", "join", "local", "global",
}  # fmt: skip


class TokenStream:
    """The tokens of one program and where the parser is in them."""

    def __init__(self, text: str) -> None:
        self.tokens = tokenize(text)
        self.lines = text.split("\n")
        self.last_line = len(text.splitlines()) or 1
        self.i = 0
        self.nest = 0  # open brackets: inside them line breaks are only spacing
        self.depth = 0

    def peek(self) -> Token:
        return self.tokens[self.i]

    def next(self) -> Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def at(self, *texts: str) -> bool:
        tok = self.tokens[self.i]
        return tok.kind in ("op", "name") and tok.text in texts

    def take(self, text: str) -> Token:
        if not self.at(text):
            raise self.fail()
        return self.next()

    def binary(self, texts: set[str] | tuple[str, ...]) -> Token | None:
        """The next token if it is one of these operators and may continue the expression."""
        tok = self.tokens[self.i]
        if tok.text in texts and tok.kind in ("op", "name") and (self.nest or not tok.nl):
            self.i += 1
            return tok
        return None

    def source(self, line: int) -> str:
        return self.lines[line - 1].strip() if 0 < line <= len(self.lines) else ""

    def fail(self) -> ScriptFault:
        """The syntax error at the next token; one on a later line is missing from the line before."""
        tok = self.peek()
        if tok.nl and self.i > 0:
            prev = self.tokens[self.i - 1]
            line, column = prev.line, prev.column + len(prev.text)
        else:
            line, column = tok.line, tok.column
        return ScriptFault(f"syntax_error_on_line:{line}:{self.source(line)}", line, column)

    def fail_at(self, tok: Token) -> ScriptFault:
        return ScriptFault(f"syntax_error_on_line:{tok.line}:{self.source(tok.line)}", tok.line, tok.column)

    def deeper(self) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            tok = self.peek()
            raise ScriptFault(
                f"syntax_error_on_line:{tok.line}:nested more than {MAX_NESTING} levels", tok.line, tok.column
            )
