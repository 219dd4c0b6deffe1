"""URScript's parser: tokens to the syntax tree, by recursive descent over grammar.ebnf (statements
here; expressions in expression_parser.py, the token stream and its errors in token_stream.py).

Line breaks end a statement only where it can end: after `=`, an operator, an open bracket
or a comma the statement goes on (`global x = # comment` with the value on the next line), and
a new statement may follow on the same line, as the controller reads it. Every token is read
once and nothing backtracks, so parsing is linear in the program; nesting deeper than
MAX_NESTING is a syntax error rather than a Python recursion fault. `def`, `sec` and `thread`
may nest; they are hoisted into one table, as the controller resolves names program-wide.
`$ N "text"` lines (program labels) are statements of their own.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

from rtde_spec.emulator.urscript.expression_parser import ExpressionParser
from rtde_spec.emulator.urscript.lexer import Token
from rtde_spec.emulator.urscript.nodes import Branch, Expr, Function, Script, ScriptFault, Stmt
from rtde_spec.emulator.urscript.token_stream import KEYWORDS

MAX_PROGRAM = 4 << 20  # characters of one program (a controller refuses much smaller ones)
_BARE = {"halt", "enter_critical", "exit_critical"}
_BLOCK_END = {"end", "elif", "else"}
KEPT_TREES = 8  # the last long programs read, kept parsed (parse_program)
KEPT_FROM = 4 << 10  # characters: a shorter program parses within a fraction of a control step
KEPT_CHARS = 1 << 20  # characters of the programs kept, all told (a tree holds ~15 bytes a character)
_kept: OrderedDict[str, Script] = OrderedDict()
_kept_lock = threading.Lock()


def parse(text: str) -> Script:
    """The whole script; a ScriptFault for the first thing it cannot read (nothing runs then)."""
    if len(text) > MAX_PROGRAM:
        raise ScriptFault(f"syntax_error_on_line:1:program over {MAX_PROGRAM} characters", 1, 1)
    return _Parser(text).script()


def parse_program(text: str) -> Script:
    """`parse(text)` for a program to run, from the last KEPT_TREES long ones when it is one of them.

    A driver sends the same program again and again (URCL's, 49 kB, for each of its tests, then
    waits 100 ms for it to connect back); parsing it was most of that time. Programs share the
    tree, which nothing changes once the checker has marked it, but each has its own tables
    (interpreter mode adds functions to its program's)."""
    with _kept_lock:
        tree = _kept.get(text)
        if tree is not None:
            _kept.move_to_end(text)
    if tree is None:
        tree = parse(text)
        if KEPT_FROM <= len(text) <= KEPT_CHARS:
            with _kept_lock:
                _kept[text] = tree
                while len(_kept) > KEPT_TREES or sum(map(len, _kept)) > KEPT_CHARS:
                    _kept.popitem(last=False)
    return Script(dict(tree.functions), list(tree.main), tree.name, tree.secondary, tree.wrapped)


class _Parser(ExpressionParser):
    def __init__(self, text: str) -> None:
        super().__init__(text)
        self.functions: dict[str, Function] = {}
        self.loops = 0
        self.in_def = 0
        self.top: list[Function] = []  # the defs not inside another, in order

    # --- statements --------------------------------------------------------------------------

    def script(self) -> Script:
        main = self.block(None)
        tok = self.peek()
        if tok.kind != "eof":
            raise self.fail_at(tok)  # an end, elif or else with nothing open
        script = Script(self.functions, main)
        top = [f for f in self.top if not f.thread]
        if not main and top:  # a program sent as `def name(): ... end` runs at once
            program = top[0]
            script.name, script.secondary, script.wrapped = program.name, program.secondary, True
            call = Expr("call", program.name, column=1, line=program.line)
            script.main = [Stmt("call", program.line, f"{program.name}()", program.name, call)]
        return script

    def block(self, opener: tuple[str, Token] | None) -> list[Stmt]:
        """Statements up to an `end`, `elif` or `else` (not taken), or the end of the text."""
        body: list[Stmt] = []
        while True:
            tok = self.peek()
            if tok.kind == "eof":
                if opener is not None:
                    what = opener[0]
                    raise ScriptFault(
                        f"syntax_error_on_line:{self.last_line}:missing end of {what}", self.last_line, 1
                    )
                return body
            if tok.kind == "name" and tok.text in _BLOCK_END:
                return body
            stmt = self.statement()
            if stmt is not None:
                body.append(stmt)

    def statement(self) -> Stmt | None:
        tok = self.peek()
        if tok.kind == "op" and tok.text == "$":
            return self.label()
        word = tok.text if tok.kind == "name" else ""
        if word in ("def", "sec", "thread"):
            self.definition()
            return None
        if word in ("if", "while"):
            return self.conditional(word)
        if word in ("break", "continue"):
            self.next()
            if not self.loops:
                raise self.fail_at(tok)
            return Stmt(word, tok.line, self.source(tok.line), word, column=tok.column)
        if word == "return":
            self.next()
            if not self.in_def:
                raise self.fail_at(tok)
            value = None if self.peek().nl or self.at(*_BLOCK_END) else self.expr()
            return Stmt("return", tok.line, self.source(tok.line), "return", value, column=tok.column)
        if word in ("kill", "join"):
            self.next()
            return Stmt(word, tok.line, self.source(tok.line), word, self.expr(), column=tok.column)
        if word in _BARE:
            self.next()
            return Stmt(word, tok.line, self.source(tok.line), word, column=tok.column)
        scope = ""
        if word in ("local", "global"):
            self.next()
            scope = word
        return self.assignment_or_call(tok, scope)

    def assignment_or_call(self, first: Token, scope: str) -> Stmt:
        start = self.peek()
        target = self.expr()
        text = self.source(first.line)
        if self.at("="):
            self.next()
            name, index = self.target(target, start)
            value = self.expr()
            return Stmt("assign", first.line, text, name, value, start.column, index, scope=scope)
        if scope or target.kind not in ("call", "run", "method"):
            raise self.fail()
        return Stmt("call", first.line, text, target.value, target, column=start.column)

    def label(self) -> Stmt:
        """`$ 7 "MoveJ"` (PolyScope writes `$ 15 "Waypoint_1" "breakAfter"`): the program tree node a
        thread is at, by its number and text; the texts after the first are PolyScope's flags."""
        tok = self.next()
        number = self.peek()
        if number.kind != "num" or number.nl or any(c in number.text for c in ".eE"):
            raise self.fail()  # (a number on the next line is missing from this one)
        self.next()
        texts: list[str] = []
        while self.peek().kind == "str" and not self.peek().nl:
            texts.append(self.next().text[1:-1])
        if not texts:
            raise self.fail()
        label = Expr("num", int(number.text), column=number.column, line=number.line)
        return Stmt("label", tok.line, self.source(tok.line), texts[0], label, column=tok.column)

    def target(self, expr: Expr, start: Token) -> tuple[str, tuple[Expr, ...]]:
        """The variable and subscripts an assignment writes: `x`, `q[0]`, `m[1][2]`, `m[1, 2]`,
        `p[0]`, a struct's field `s.kp` (URCL's `pd_controller_gains.kp = [...]`); a matrix's row
        and column are one subscript, a `pair`, a field one `member`."""
        index: list[Expr] = []
        while expr.kind in ("index", "field"):
            if expr.kind == "field":
                index.insert(0, Expr("member", expr.value, column=expr.column, line=expr.line))
            else:
                index.insert(0, _subscript(expr.items[1:], expr))
            expr = expr.items[0]
        if expr.kind == "pose" and expr.value == "p" and len(expr.items) in (1, 2):
            return "p", (_subscript(expr.items, expr), *index)
        if expr.kind != "name":
            raise self.fail_at(start)
        return expr.value, tuple(index)

    def definition(self) -> None:
        head = self.next()
        name = self.next()
        if name.kind != "name" or name.text in KEYWORDS:
            raise self.fail_at(name)
        self.take("(")
        params: list[str] = []
        defaults: list[Expr | None] = []
        while not self.at(")"):
            param = self.next()
            if param.kind != "name" or param.text in KEYWORDS:
                raise self.fail_at(param)
            params.append(param.text)
            defaults.append(self.expr() if self.at("=") and self.next() else None)
            if not self.at(")"):
                self.take(",")
        self.take(")")
        self.take(":")
        if head.text == "thread" and params:
            raise self.fail_at(name)
        loops, self.loops = self.loops, 0
        self.in_def += 1
        self.deeper()
        body = self.block((name.text, head))
        self.depth -= 1
        self.in_def -= 1
        self.loops = loops
        self.close()
        function = Function(
            name.text,
            tuple(params),
            body,
            head.line,
            head.text == "sec",
            head.text == "thread",
            tuple(defaults),
        )
        self.functions[name.text] = function
        if not self.in_def:
            self.top.append(function)

    def conditional(self, word: str) -> Stmt:
        head = self.next()
        branches: list[Branch] = []
        self.deeper()
        start = self.peek()
        cond = self.expr()
        self.take(":")
        if word == "while":
            self.loops += 1
            body = self.block((f"while on line {head.line}", head))
            self.loops -= 1
            branches.append(Branch(cond, body, head.line, start.column))
        else:
            what = (f"if on line {head.line}", head)
            branches.append(Branch(cond, self.block(what), head.line, start.column))
            while self.at("elif"):
                tok = self.next()
                start = self.peek()
                cond = self.expr()
                self.take(":")
                branches.append(Branch(cond, self.block(what), tok.line, start.column))
            if self.at("else"):
                tok = self.next()
                self.take(":")
                branches.append(Branch(None, self.block(what), tok.line, tok.column))
        self.depth -= 1
        self.close()
        return Stmt(
            word, head.line, self.source(head.line), word, column=head.column, branches=tuple(branches)
        )

    def close(self) -> None:
        """A block's `end`; an `elif` or `else` no `if` owns is the error, on its own line (not
        an `end` missing from the line before)."""
        if self.at("elif", "else"):
            raise self.fail_at(self.peek())
        self.take("end")


def _subscript(indices: tuple[Expr, ...], where: Expr) -> Expr:
    """One subscript of an assignment target: its index, or a `pair` of row and column."""
    if len(indices) == 1:
        return indices[0]
    return Expr("pair", items=indices, column=where.column, line=where.line)
