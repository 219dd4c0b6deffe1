"""URScript expressions, by recursive descent over grammar.ebnf's `expression` rules.

Precedence is the grammar's, lowest first: or/xor, and, not, comparisons, + -, * / %, unary
signs, then subscripts, fields and method calls (`camera.getTarget()`, a remote procedure call)
after an atom. A subscript holds one index (`q[0]`) or two, a
matrix's row and column (`m[1, 0]`, the Script Manual's matrix form since 3.14 / 5.9). Inside
brackets a line break is only spacing; elsewhere an operator at the start of a line starts a new
statement, as the controller reads it.
"""

from __future__ import annotations

from rtde_spec.emulator.urscript.nodes import Expr
from rtde_spec.emulator.urscript.token_stream import KEYWORDS, TokenStream

COMPARISONS = {"==", "!=", "<", "<=", ">", ">="}


class ExpressionParser(TokenStream):
    """The expression half of the parser; parser.py adds the statements."""

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
                value = Expr("index", items=(value, *self.subscript()), column=tok.column, line=tok.line)
            elif (tok := self.binary((".",))) is not None:
                name = self.next()
                if name.kind != "name":
                    raise self.fail_at(name)
                if self.at("(") and (self.nest or not self.peek().nl):  # proxy.getTarget(): an RPC call
                    args, kwargs = self.arguments()
                    items = (value, *args)
                    value = Expr("method", name.text, items, kwargs, column=name.column, line=name.line)
                else:
                    value = Expr("field", name.text, (value,), column=name.column, line=name.line)
            else:
                return value

    def subscript(self) -> tuple[Expr, ...]:
        """After `[`: one index, or a matrix's row and column, up to the `]`."""
        self.nest += 1
        indices = [self.expr()]
        if self.at(","):
            self.next()
            indices.append(self.expr())
        self.take("]")
        self.nest -= 1
        return tuple(indices)

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
