"""A small URScript parser: the lines and `def name(): ... end` programs clients send to 30001-30003.

It reads what motion and I/O programs use: calls with positional and keyword
arguments (`movej([0, -1.57, 0, 0, 0, 0], a=1.2, v=0.5)`), expressions
(`urscript_expr.py`: arithmetic, comparisons, `and`/`or`/`xor`/`not`, indexing),
`x = expr` and `q[0] = expr` (with optional `local`/`global`), `def`/`sec` with
parameters, `if`/`elif`/`else`, `while`, `break`, `continue`, `return`, and comments.
Threads (`thread`, `run`, `join`, `kill`) are a ScriptFault naming the line and
column, which the controller reports as a runtime exception instead of dropping the
program; so are syntax errors, found before anything runs, as a controller compiles first.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from rtde_spec.emulator.urscript_expr import (
    Expr,
    ExprParser,
    ScriptFault,
    Token,
    strip_comment,
    tokenize,
)

__all__ = [
    "Branch",
    "Expr",
    "Function",
    "Script",
    "ScriptFault",
    "Stmt",
    "parse",
    "parse_statement",
    "tokenize",
]

UNSUPPORTED = {"for", "thread", "run", "join", "kill"}
# lines that open, continue or close a block, or leave one: parsed here, run by program.py
_HEADS = {"if", "elif", "while"}
_WORDS = {"else", "end", "break", "continue", "return"}


@dataclass(frozen=True)
class Branch:
    """One arm of an `if` (cond None for `else`), or a `while`'s condition and body."""

    cond: Expr | None
    body: list[Stmt]
    line: int
    column: int = 0


@dataclass(frozen=True)
class Stmt:
    """One statement. kind: call, assign, if, while, return, break, continue (and, from
    `parse_statement` only, the block lines elif, else, end). `column` is where a
    condition starts; `index` the subscripts of an assignment target `q[0] = ...`."""

    kind: str
    line: int
    text: str
    name: str = ""
    expr: Expr | None = None
    column: int = 0
    index: tuple[Expr, ...] = ()
    branches: tuple[Branch, ...] = ()


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


def parse_statement(text: str, line: int) -> Stmt | None:
    """One line's statement (None for a blank or comment line)."""
    tokens = tokenize(text, line)
    if not tokens:
        return None
    parser = ExprParser(tokens, line, text)
    first = tokens[0]
    word = first[1] if first[0] == "name" else ""
    if word in UNSUPPORTED:
        raise ScriptFault(f"not supported by the emulator: {word}", line, first[2])
    if word in _HEADS or word in _WORDS:
        return _block_line(parser, word, first, text.strip())
    if word in ("local", "global"):
        parser.pos += 1
    stmt = _assignment(parser, text.strip())
    if stmt is None:
        expr = parser.expr()
        if expr.kind != "call":
            raise parser.fail()
        stmt = Stmt("call", line, text.strip(), expr.value, expr)
    if not parser.at_end():
        raise parser.fail()
    return stmt


def _block_line(parser: ExprParser, word: str, first: Token, text: str) -> Stmt:
    parser.pos += 1
    line = parser.line
    if word in _HEADS:
        start = parser.peek()
        cond = parser.expr()
        parser.take(":")
        stmt = Stmt(word, line, text, word, cond, column=start[2] if start else first[2])
    elif word == "else":
        parser.take(":")
        stmt = Stmt(word, line, text, word, column=first[2])
    elif word == "return" and not parser.at_end():
        stmt = Stmt(word, line, text, word, parser.expr(), column=first[2])
    else:
        stmt = Stmt(word, line, text, word, column=first[2])
    if not parser.at_end():
        raise parser.fail()
    return stmt


def _assignment(parser: ExprParser, text: str) -> Stmt | None:
    """`name = expr` or `name[i]... = expr`, or None (nothing consumed) if the line is no assignment."""
    head = parser.peek()
    if head is None or head[0] != "name":
        return None
    start = parser.pos
    parser.pos += 1
    index: list[Expr] = []
    try:
        while (tok := parser.peek()) is not None and tok[1] == "[":
            parser.pos += 1
            index.append(parser.expr())
            parser.take("]")
    except ScriptFault:
        parser.pos = start
        return None
    tok = parser.peek()
    if tok is None or tok[1] != "=":
        parser.pos = start
        return None
    parser.pos += 1
    return Stmt("assign", parser.line, text, head[1], parser.expr(), column=head[2], index=tuple(index))


_DEF = re.compile(r"^\s*(def|sec)\s+([A-Za-z_]\w*)\s*\(([^)]*)\)\s*:\s*(?:#.*)?$")


@dataclass
class _Open:
    """A block whose `end` has not come: a def (with its Function), an if or a while."""

    head: Stmt
    branches: list[Branch]
    function: Function | None = None
    has_else: bool = False


def parse(text: str) -> Script:
    """The whole script; a ScriptFault for the first line it cannot read (nothing runs then)."""
    functions: dict[str, Function] = {}
    main: list[Stmt] = []
    stack: list[_Open] = []
    lines = text.splitlines()
    number = 0
    while number < len(lines):
        start = number + 1
        raw = lines[number]
        number += 1
        while _open_brackets(raw) > 0 and number < len(lines):  # a call spread over lines
            raw += " " + lines[number].strip()
            number += 1
        found = _DEF.match(raw)
        if found:
            if stack:
                raise ScriptFault(f"not supported by the emulator: nested {found.group(1)}", start, 1)
            params = tuple(p.strip() for p in found.group(3).split(",") if p.strip())
            function = Function(found.group(2), params, line=start, secondary=found.group(1) == "sec")
            head = Stmt(found.group(1), start, raw.strip(), function.name)
            stack.append(_Open(head, [Branch(None, function.body, start)], function))
            continue
        stmt = parse_statement(raw, start)
        if stmt is None:
            continue
        body = stack[-1].branches[-1].body if stack else main
        if stmt.kind in ("if", "while"):
            stack.append(_Open(stmt, [Branch(stmt.expr, [], start, stmt.column)]))
        elif stmt.kind in ("elif", "else"):
            block = stack[-1] if stack else None
            if block is None or block.head.kind != "if" or block.has_else:
                raise _syntax(stmt, raw)  # an elif or else without its if, or after the else
            block.has_else = stmt.kind == "else"
            block.branches.append(Branch(stmt.expr, [], start, stmt.column))
        elif stmt.kind == "end":
            if not stack:
                raise _syntax(stmt, raw)
            block = stack.pop()
            if block.function is not None:
                functions[block.function.name] = block.function
            else:
                head = block.head
                closed = Stmt(head.kind, head.line, head.text, branches=tuple(block.branches))
                (stack[-1].branches[-1].body if stack else main).append(closed)
        else:
            _check_placement(stmt, stack, raw)
            body.append(stmt)
    if stack:
        block = stack[-1]
        head = block.head
        what = head.name if block.function is not None else f"{head.kind} on line {head.line}"
        raise ScriptFault(f"syntax_error_on_line:{len(lines)}:missing end of {what}", len(lines), 1)
    script = Script(functions, main)
    if not main and functions:  # a program sent as `def name(): ... end` runs at once
        program = next(iter(functions.values()))
        script.name, script.secondary = program.name, program.secondary
        script.main = [
            Stmt("call", program.line, f"{program.name}()", program.name, Expr("call", program.name))
        ]
    return script


def _check_placement(stmt: Stmt, stack: list[_Open], raw: str) -> None:
    """`break`/`continue` only inside a while, `return` only inside a def, as the compiler checks."""
    if stmt.kind in ("break", "continue") and not any(b.head.kind == "while" for b in stack):
        raise _syntax(stmt, raw)
    if stmt.kind == "return" and not any(b.function is not None for b in stack):
        raise _syntax(stmt, raw)


def _syntax(stmt: Stmt, raw: str) -> ScriptFault:
    """A block word where it cannot stand: the controller's syntax error, at the word."""
    column = len(raw) - len(raw.lstrip()) + 1
    return ScriptFault(f"syntax_error_on_line:{stmt.line}:{stmt.text}", stmt.line, column)


def _open_brackets(text: str) -> int:
    code = strip_comment(text)
    return code.count("(") + code.count("[") - code.count(")") - code.count("]")
