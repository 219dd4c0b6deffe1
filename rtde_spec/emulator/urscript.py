"""A small URScript parser: the lines and `def name(): ... end` programs clients send to 30001-30003.

It reads what motion and I/O programs use: calls with positional and keyword
arguments (`movej([0, -1.57, 0, 0, 0, 0], a=1.2, v=0.5)`), numbers, strings, lists,
poses `p[...]`, arithmetic, names, `x = expr` (with optional `local`/`global`),
`def`/`sec` with parameters, and comments. Anything else (`if`, `while`, `thread`,
...) is a ScriptFault naming the line and column, which the controller reports as
a runtime exception instead of dropping the program.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

TOKEN = re.compile(
    r"\s*(?:(?P<num>\d+\.\d*(?:[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?|\d+(?:[eE][-+]?\d+)?)"
    r"|(?P<str>\"[^\"]*\"|'[^']*')|(?P<name>[A-Za-z_]\w*)|(?P<op>==|!=|<=|>=|[-+*/%()\[\],=:<>]))"
)
UNSUPPORTED = {
    "if",
    "elif",
    "else",
    "while",
    "for",
    "thread",
    "run",
    "join",
    "kill",
    "return",
    "break",
    "continue",
}


class ScriptFault(Exception):
    """A program the emulator cannot run: text as a controller reports it, and where."""

    def __init__(self, text: str, line: int = 0, column: int = 0) -> None:
        super().__init__(f"line {line}: {text}")
        self.text, self.line, self.column = text, line, column


@dataclass(frozen=True)
class Expr:
    kind: str  # num, str, bool, name, list, pose, call, neg, binop
    value: Any = None
    items: tuple[Expr, ...] = ()
    kwargs: tuple[tuple[str, Expr], ...] = ()
    column: int = 0


@dataclass(frozen=True)
class Stmt:
    kind: str  # call, assign
    line: int
    text: str
    name: str = ""
    expr: Expr | None = None


@dataclass
class Function:
    name: str
    params: tuple[str, ...]
    body: list[Stmt] = field(default_factory=list)
    line: int = 0
    secondary: bool = False


@dataclass
class Script:
    """A parsed script: its functions, and the top-level statements to run (a call of the program)."""

    functions: dict[str, Function]
    main: list[Stmt]
    name: str = ""
    secondary: bool = False


def tokenize(text: str, line: int) -> list[tuple[str, str, int]]:
    """(kind, text, column 1-based); comments dropped."""
    out: list[tuple[str, str, int]] = []
    pos = 0
    code = _strip_comment(text)
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


def _strip_comment(text: str) -> str:
    quote = ""
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return text[:i]
    return text


class _Parser:
    def __init__(self, tokens: list[tuple[str, str, int]], line: int, text: str) -> None:
        self.tokens, self.pos, self.line, self.text = tokens, 0, line, text

    def fail(self) -> ScriptFault:
        column = self.tokens[self.pos][2] if self.pos < len(self.tokens) else len(self.text.rstrip()) + 1
        return ScriptFault(f"syntax_error_on_line:{self.line}:{self.text.strip()}", self.line, column)

    def peek(self, offset: int = 0) -> tuple[str, str, int] | None:
        i = self.pos + offset
        return self.tokens[i] if i < len(self.tokens) else None

    def take(self, text: str | None = None) -> tuple[str, str, int]:
        tok = self.peek()
        if tok is None or (text is not None and tok[1] != text):
            raise self.fail()
        self.pos += 1
        return tok

    def at_end(self) -> bool:
        return self.pos >= len(self.tokens)

    def expr(self) -> Expr:
        left = self.term()
        while (tok := self.peek()) is not None and tok[1] in "+-" and tok[0] == "op":
            self.pos += 1
            left = Expr("binop", tok[1], (left, self.term()), column=tok[2])
        return left

    def term(self) -> Expr:
        left = self.unary()
        while (tok := self.peek()) is not None and tok[0] == "op" and tok[1] in ("*", "/", "%"):
            self.pos += 1
            left = Expr("binop", tok[1], (left, self.unary()), column=tok[2])
        return left

    def unary(self) -> Expr:
        tok = self.peek()
        if tok is not None and tok[0] == "op" and tok[1] in "+-":
            self.pos += 1
            inner = self.unary()
            return inner if tok[1] == "+" else Expr("neg", items=(inner,), column=tok[2])
        return self.atom()

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


def parse_statement(text: str, line: int) -> Stmt | None:
    """One line's statement (None for a blank or comment line)."""
    tokens = tokenize(text, line)
    if not tokens:
        return None
    parser = _Parser(tokens, line, text)
    first = tokens[0]
    if first[0] == "name" and first[1] in UNSUPPORTED:
        raise ScriptFault(f"not supported by the emulator: {first[1]}", line, first[2])
    if first[0] == "name" and first[1] in ("local", "global"):
        parser.pos += 1
    head = parser.peek()
    nxt = parser.peek(1)
    if head is not None and head[0] == "name" and nxt is not None and nxt[1] == "=":
        parser.pos += 2
        stmt = Stmt("assign", line, text.strip(), head[1], parser.expr())
    else:
        expr = parser.expr()
        if expr.kind != "call":
            raise parser.fail()
        stmt = Stmt("call", line, text.strip(), expr.value, expr)
    if not parser.at_end():
        raise parser.fail()
    return stmt


_DEF = re.compile(r"^\s*(def|sec)\s+([A-Za-z_]\w*)\s*\(([^)]*)\)\s*:\s*(?:#.*)?$")


def parse(text: str) -> Script:
    """The whole script; a ScriptFault for the first line it cannot read (nothing runs then)."""
    functions: dict[str, Function] = {}
    main: list[Stmt] = []
    current: Function | None = None
    lines = text.splitlines()
    number = 0
    while number < len(lines):
        start = number + 1
        raw = lines[number]
        number += 1
        while _open_brackets(raw) > 0 and number < len(lines):  # a call spread over lines
            raw += " " + lines[number].strip()
            number += 1
        stripped = _strip_comment(raw).strip()
        found = _DEF.match(raw)
        if found:
            if current is not None:
                raise ScriptFault(f"not supported by the emulator: nested {found.group(1)}", start, 1)
            params = tuple(p.strip() for p in found.group(3).split(",") if p.strip())
            current = Function(found.group(2), params, line=start, secondary=found.group(1) == "sec")
        elif stripped == "end":
            if current is None:
                raise ScriptFault(f"syntax_error_on_line:{start}:end", start, raw.index("end") + 1)
            functions[current.name] = current
            current = None
        else:
            stmt = parse_statement(raw, start)
            if stmt is not None:
                (current.body if current is not None else main).append(stmt)
    if current is not None:
        raise ScriptFault(f"syntax_error_on_line:{len(lines)}:missing end of {current.name}", len(lines), 1)
    script = Script(functions, main)
    if not main and functions:  # a program sent as `def name(): ... end` runs at once
        program = next(iter(functions.values()))
        script.name, script.secondary = program.name, program.secondary
        script.main = [
            Stmt("call", program.line, f"{program.name}()", program.name, Expr("call", program.name))
        ]
    return script


def _open_brackets(text: str) -> int:
    code = _strip_comment(text)
    return code.count("(") + code.count("[") - code.count(")") - code.count("]")
