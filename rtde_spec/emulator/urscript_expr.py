"""URScript expressions: tokens and the expression grammar, with the Script manual's precedence.

From loosest to tightest: `or`/`xor`, `and`, `not`, comparisons (`== != < <= > >=`),
`+ -`, `* / %`, unary `-`, then calls, indexing `q[0]` and atoms (numbers, strings,
`True`/`False`, names, lists, poses `p[...]`, parentheses) — the order Python uses,
which URScript follows. Kept apart from the statement parser so each stays small.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

TOKEN = re.compile(
    r"\s*(?:(?P<num>\d+\.\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?|\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<str>\"[^\"]*\"|'[^']*')|(?P<name>[A-Za-z_]\w*)|(?P<op>==|!=|<=|>=|[-+*/%()\[\],=:<>]))"
)
COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
# words that are never a value: an expression meeting one where a value belongs is a syntax error
KEYWORDS = {
    "and", "or", "xor", "not", "if", "elif", "else", "while", "end",
    "return", "break", "continue", "def", "sec",
}  # fmt: skip
Token = tuple[str, str, int]  # kind, text, column (1-based)


class ScriptFault(Exception):
    """A program the emulator cannot run: text as a controller reports it, and where."""

    def __init__(self, text: str, line: int = 0, column: int = 0) -> None:
        super().__init__(f"line {line}: {text}")
        self.text, self.line, self.column = text, line, column


@dataclass(frozen=True)
class Expr:
    # num, str, bool, name, list, pose, call, neg, binop, compare, logic (and/or/xor), not, index
    kind: str
    value: Any = None
    items: tuple[Expr, ...] = ()
    kwargs: tuple[tuple[str, Expr], ...] = ()
    column: int = 0


def tokenize(text: str, line: int) -> list[Token]:
    """(kind, text, column 1-based); comments dropped."""
    out: list[Token] = []
    pos = 0
    code = strip_comment(text)
    while pos < len(code):
        if code[pos:].strip() == "":
            break
        match = TOKEN.match(code, pos)
        if match is None or match.end() == pos:
            bad = len(code) - len(code[pos:].lstrip()) + 1
            raise ScriptFault(f"syntax_error_on_line:{line}:{text.strip()}", line, bad)
        kind = match.lastgroup or "op"
        start = match.start(kind) + 1
        out.append((kind, match.group(kind), start))
        pos = match.end()
    return out


def strip_comment(text: str) -> str:
    quote = ""
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return text[:i]
    return text


class ExprParser:
    """Reads one line's tokens; `fail()` is the controller's syntax error at the current token."""

    def __init__(self, tokens: list[Token], line: int, text: str) -> None:
        self.tokens, self.pos, self.line, self.text = tokens, 0, line, text

    def fail(self) -> ScriptFault:
        column = self.tokens[self.pos][2] if self.pos < len(self.tokens) else len(self.text.rstrip()) + 1
        return ScriptFault(f"syntax_error_on_line:{self.line}:{self.text.strip()}", self.line, column)

    def peek(self, offset: int = 0) -> Token | None:
        i = self.pos + offset
        return self.tokens[i] if i < len(self.tokens) else None

    def take(self, text: str | None = None) -> Token:
        tok = self.peek()
        if tok is None or (text is not None and tok[1] != text):
            raise self.fail()
        self.pos += 1
        return tok

    def at_end(self) -> bool:
        return self.pos >= len(self.tokens)

    def _word(self, *words: str) -> Token | None:
        """The next token if it is one of these keywords (consumed), else None."""
        tok = self.peek()
        if tok is not None and tok[0] == "name" and tok[1] in words:
            self.pos += 1
            return tok
        return None

    def _op(self, *ops: str) -> Token | None:
        tok = self.peek()
        if tok is not None and tok[0] == "op" and tok[1] in ops:
            self.pos += 1
            return tok
        return None

    def expr(self) -> Expr:
        left = self.conjunction()
        while (tok := self._word("or", "xor")) is not None:
            left = Expr("logic", tok[1], (left, self.conjunction()), column=tok[2])
        return left

    def conjunction(self) -> Expr:
        left = self.negation()
        while (tok := self._word("and")) is not None:
            left = Expr("logic", "and", (left, self.negation()), column=tok[2])
        return left

    def negation(self) -> Expr:
        tok = self._word("not")
        if tok is not None:
            return Expr("not", items=(self.negation(),), column=tok[2])
        return self.comparison()

    def comparison(self) -> Expr:
        left = self.sum()
        while (tok := self._op(*COMPARISONS)) is not None:
            left = Expr("compare", tok[1], (left, self.sum()), column=tok[2])
        return left

    def sum(self) -> Expr:
        left = self.term()
        while (tok := self._op("+", "-")) is not None:
            left = Expr("binop", tok[1], (left, self.term()), column=tok[2])
        return left

    def term(self) -> Expr:
        left = self.unary()
        while (tok := self._op("*", "/", "%")) is not None:
            left = Expr("binop", tok[1], (left, self.unary()), column=tok[2])
        return left

    def unary(self) -> Expr:
        tok = self._op("+", "-")
        if tok is not None:
            inner = self.unary()
            return inner if tok[1] == "+" else Expr("neg", items=(inner,), column=tok[2])
        return self.postfix()

    def postfix(self) -> Expr:
        value = self.atom()
        while (tok := self._op("[")) is not None:
            index = self.expr()
            self.take("]")
            value = Expr("index", items=(value, index), column=tok[2])
        return value

    def atom(self) -> Expr:
        tok = self.peek()
        if tok is None:
            raise self.fail()
        kind, text, column = tok
        if kind == "num":
            self.pos += 1
            return Expr("num", float(text) if any(c in text for c in ".eE") else int(text), column=column)
        if kind == "str":
            self.pos += 1
            return Expr("str", text[1:-1], column=column)
        if kind == "name":
            if text in KEYWORDS:
                raise self.fail()
            self.pos += 1
            if text in ("True", "False", "true", "false"):
                return Expr("bool", text.lower() == "true", column=column)
            nxt = self.peek()
            if text == "p" and nxt is not None and nxt[1] == "[":
                return Expr("pose", items=self.sequence("[", "]"), column=column)
            if nxt is not None and nxt[1] == "(":
                args, kwargs = self.arguments()
                return Expr("call", text, args, kwargs, column=column)
            return Expr("name", text, column=column)
        if text == "[":
            return Expr("list", items=self.sequence("[", "]"), column=column)
        if text == "(":
            self.pos += 1
            inner = self.expr()
            self.take(")")
            return inner
        raise self.fail()

    def sequence(self, open_: str, close: str) -> tuple[Expr, ...]:
        self.take(open_)
        items: list[Expr] = []
        while (tok := self.peek()) is not None and tok[1] != close:
            items.append(self.expr())
            if (nxt := self.peek()) is not None and nxt[1] == ",":
                self.pos += 1
        self.take(close)
        return tuple(items)

    def arguments(self) -> tuple[tuple[Expr, ...], tuple[tuple[str, Expr], ...]]:
        self.take("(")
        args: list[Expr] = []
        kwargs: list[tuple[str, Expr]] = []
        while (tok := self.peek()) is not None and tok[1] != ")":
            nxt = self.peek(1)
            if tok[0] == "name" and nxt is not None and nxt[1] == "=":
                self.pos += 2
                kwargs.append((tok[1], self.expr()))
            elif kwargs:
                raise self.fail()  # a positional argument after a named one
            else:
                args.append(self.expr())
            if (sep := self.peek()) is not None and sep[1] == ",":
                self.pos += 1
            elif sep is None or sep[1] != ")":
                raise self.fail()
        self.take(")")
        return tuple(args), tuple(kwargs)
