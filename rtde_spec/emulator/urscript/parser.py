"""URScript's parser: tokens to the syntax tree, by recursive descent over grammar.ebnf.

Line breaks end a statement only where it can end: after `=`, an operator, an open bracket
or a comma the statement goes on (`global x = # comment` with the value on the next line), and
a new statement may follow on the same line, as the controller reads it. Every token is read
once and nothing backtracks, so parsing is linear in the program; nesting deeper than
MAX_NESTING is a syntax error rather than a Python recursion fault. `def`, `sec` and `thread`
may nest; they are hoisted into one table, as the controller resolves names program-wide.
"""

from __future__ import annotations

from rtde_spec.emulator.urscript.lexer import Token, tokenize
from rtde_spec.emulator.urscript.nodes import Branch, Expr, Function, Script, ScriptFault, Stmt

MAX_NESTING = 100  # brackets, operators and blocks inside one another
MAX_PROGRAM = 4 << 20  # characters of one program (a controller refuses much smaller ones)
KEYWORDS = {
    "and", "or", "xor", "not", "if", "elif", "else", "while", "end", "return", "break",
    "continue", "def", "sec", "thread", "run", "kill", "join", "local", "global",
}  # fmt: skip
COMPARISONS = {"==", "!=", "<", "<=", ">", ">="}
_BARE = {"halt", "enter_critical", "exit_critical"}
_BLOCK_END = {"end", "elif", "else"}


def parse(text: str) -> Script:
    """The whole script; a ScriptFault for the first thing it cannot read (nothing runs then)."""
    if len(text) > MAX_PROGRAM:
        raise ScriptFault(f"syntax_error_on_line:1:program over {MAX_PROGRAM} characters", 1, 1)
    return _Parser(text).script()


class _Parser:
    def __init__(self, text: str) -> None:
        self.tokens = tokenize(text)
        self.lines = text.split("\n")
        self.last_line = len(text.splitlines()) or 1
        self.i = 0
        self.nest = 0  # open brackets: inside them line breaks are only spacing
        self.depth = 0
        self.functions: dict[str, Function] = {}
        self.loops = 0
        self.in_def = 0
        self.top: list[Function] = []  # the defs not inside another, in order

    # --- tokens ------------------------------------------------------------------------------

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
        if scope or target.kind not in ("call", "run"):
            raise self.fail()
        return Stmt("call", first.line, text, target.value, target, column=start.column)

    def target(self, expr: Expr, start: Token) -> tuple[str, tuple[Expr, ...]]:
        """The variable and subscripts an assignment writes: `x`, `q[0]`, `m[1][2]`, `p[0]`."""
        index: list[Expr] = []
        while expr.kind == "index":
            index.insert(0, expr.items[1])
            expr = expr.items[0]
        if expr.kind == "pose" and expr.value == "p" and len(expr.items) == 1:
            return "p", (expr.items[0], *index)
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
        self.take("end")
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
                if self.at("elif", "else"):
                    raise self.fail_at(self.peek())
        self.depth -= 1
        self.take("end")
        return Stmt(
            word, head.line, self.source(head.line), word, column=head.column, branches=tuple(branches)
        )

    # --- expressions -------------------------------------------------------------------------

    def binary(self, texts: set[str] | tuple[str, ...]) -> Token | None:
        """The next token if it is one of these operators and may continue the expression."""
        tok = self.tokens[self.i]
        if tok.text in texts and tok.kind in ("op", "name") and (self.nest or not tok.nl):
            self.i += 1
            return tok
        return None

    def expr(self) -> Expr:
        self.deeper()
        left = self.conjunction()
        while (tok := self.binary(("or", "xor"))) is not None:
            left = Expr("logic", tok.text, (left, self.conjunction()), column=tok.column, line=tok.line)
        self.depth -= 1
        return left

    def conjunction(self) -> Expr:
        left = self.negation()
        while (tok := self.binary(("and",))) is not None:
            left = Expr("logic", "and", (left, self.negation()), column=tok.column, line=tok.line)
        return left

    def negation(self) -> Expr:
        if self.at("not"):
            tok = self.next()
            self.deeper()
            inner = self.negation()
            self.depth -= 1
            return Expr("not", items=(inner,), column=tok.column, line=tok.line)
        return self.comparison()

    def comparison(self) -> Expr:
        left = self.sum()
        while (tok := self.binary(COMPARISONS)) is not None:
            left = Expr("compare", tok.text, (left, self.sum()), column=tok.column, line=tok.line)
        return left

    def sum(self) -> Expr:
        left = self.term()
        while (tok := self.binary(("+", "-"))) is not None:
            left = Expr("binop", tok.text, (left, self.term()), column=tok.column, line=tok.line)
        return left

    def term(self) -> Expr:
        left = self.unary()
        while (tok := self.binary(("*", "/", "%"))) is not None:
            left = Expr("binop", tok.text, (left, self.unary()), column=tok.column, line=tok.line)
        return left

    def unary(self) -> Expr:
        if self.peek().kind == "op" and self.at("+", "-"):
            tok = self.next()
            self.deeper()
            inner = self.unary()
            self.depth -= 1
            return inner if tok.text == "+" else Expr("neg", items=(inner,), column=tok.column, line=tok.line)
        return self.postfix()

    def postfix(self) -> Expr:
        value = self.atom()
        while True:
            if (tok := self.binary(("[",))) is not None:
                self.nest += 1
                index = self.expr()
                self.take("]")
                self.nest -= 1
                value = Expr("index", items=(value, index), column=tok.column, line=tok.line)
            elif (tok := self.binary((".",))) is not None:
                name = self.next()
                if name.kind != "name":
                    raise self.fail_at(name)
                value = Expr("field", name.text, (value,), column=name.column, line=name.line)
            else:
                return value

    def atom(self) -> Expr:
        tok = self.next()
        kind, text, line, column = tok.kind, tok.text, tok.line, tok.column
        if kind == "num":
            number = float(text) if any(c in text for c in ".eE") else int(text)
            return Expr("num", number, column=column, line=line)
        if kind == "str":
            return Expr("str", text[1:-1], column=column, line=line)
        if kind == "name":
            if text == "run":
                name = self.next()
                if name.kind != "name" or name.text in KEYWORDS:
                    raise self.fail_at(name)
                self.take("(")
                self.take(")")
                return Expr("run", name.text, column=column, line=line)
            if text in KEYWORDS:
                self.i -= 1
                raise self.fail()
            if text in ("True", "False", "true", "false"):
                return Expr("bool", text.lower() == "true", column=column, line=line)
            if text == "p" and self.at("["):
                return Expr("pose", "p", self.sequence("]"), column=column, line=line)
            if self.at("(") and (self.nest or not self.peek().nl):
                args, kwargs = self.arguments()
                return Expr("call", text, args, kwargs, column=column, line=line)
            return Expr("name", text, column=column, line=line)
        if text == "[":
            self.i -= 1
            return Expr("list", items=self.sequence("]"), column=column, line=line)
        if text == "(":
            self.nest += 1
            inner = self.expr()
            self.take(")")
            self.nest -= 1
            return inner
        self.i -= 1
        raise self.fail()

    def sequence(self, close: str) -> tuple[Expr, ...]:
        self.next()  # the open bracket
        self.nest += 1
        items: list[Expr] = []
        while not self.at(close):
            items.append(self.expr())
            if not self.at(close):
                self.take(",")
        self.next()
        self.nest -= 1
        return tuple(items)

    def arguments(self) -> tuple[tuple[Expr, ...], tuple[tuple[str, Expr], ...]]:
        self.take("(")
        self.nest += 1
        args: list[Expr] = []
        kwargs: list[tuple[str, Expr]] = []
        while not self.at(")"):
            tok = self.peek()
            if tok.kind == "name" and self.tokens[self.i + 1].text == "=":
                self.i += 2
                kwargs.append((tok.text, self.expr()))
            elif kwargs:
                raise self.fail()  # a positional argument after a named one
            else:
                args.append(self.expr())
            if not self.at(")"):
                self.take(",")
        self.next()
        self.nest -= 1
        return tuple(args), tuple(kwargs)
