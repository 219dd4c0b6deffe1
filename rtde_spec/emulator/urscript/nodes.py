"""The syntax tree the parser builds and the checker and interpreter read, and ScriptFault, the
controller's error (syntax, compile or runtime) with the line and column it names."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


class ScriptFault(Exception):
    """A program the emulator cannot run: text as a controller reports it, and where."""

    def __init__(self, text: str, line: int = 0, column: int = 0) -> None:
        super().__init__(f"line {line}: {text}")
        self.text, self.line, self.column = text, line, column

    @classmethod
    def name_not_found(cls, name: str, line: int, column: int) -> ScriptFault:
        """An unknown name as a controller reports it, closing colon included: URSim answers
        `calldoesntexist()` with "compile_error_name_not_found:calldoesntexist:" (URCL's
        tests/test_primary_client.cpp:455), robots with "compile_error_name_not_found:get_tcp_pose:"."""
        return cls(f"compile_error_name_not_found:{name}:", line, column)


@dataclass(eq=False)
class Expr:
    """kind: num, str, bool, name, list, pose, call, run, neg, binop, compare, logic (and/or/xor),
    not, index (items: the value and one index, or a matrix's row and column), field, method (a
    remote procedure call `handle.name(args)`: items the handle, then the arguments), and in an
    assignment's subscripts pair (a matrix's row and column). `user` is set by the checker when
    evaluating may call a user function (which may wait, so the interpreter evaluates it step by
    step)."""

    kind: str
    value: Any = None
    items: tuple[Expr, ...] = ()
    kwargs: tuple[tuple[str, Expr], ...] = ()
    column: int = 0
    line: int = 0
    user: bool = False
    call: Stmt | None = field(default=None, repr=False)  # a call's statement form, made once (interpreter)


@dataclass(frozen=True)
class Branch:
    """One arm of an `if` (cond None for `else`), or a `while`'s condition and body."""

    cond: Expr | None
    body: list[Stmt]
    line: int
    column: int = 0


@dataclass(frozen=True)
class Stmt:
    """One statement. kind: call (an expression statement), assign, if, while, return, break,
    continue, kill, join, halt, enter_critical, exit_critical, label (`$ 3 "MoveJ"`: name the text,
    expr the number). `scope` is "local"/"global" when
    the assignment says so; `index` the subscripts of an assignment target `q[0] = ...` (`m[1, 0]`
    is one subscript, a `pair`)."""

    kind: str
    line: int
    text: str
    name: str = ""
    expr: Expr | None = None
    column: int = 0
    index: tuple[Expr, ...] = ()
    branches: tuple[Branch, ...] = ()
    scope: str = ""


@dataclass
class Function:
    """A `def`, `sec` or `thread` (threads take no parameters). Nested ones are hoisted: the
    controller resolves every function name in one program-wide table."""

    name: str
    params: tuple[str, ...]
    body: list[Stmt] = field(default_factory=list)
    line: int = 0
    secondary: bool = False
    thread: bool = False
    defaults: tuple[Expr | None, ...] = ()


@dataclass
class Script:
    """A parsed script: its functions and threads, and the top-level statements to run."""

    functions: dict[str, Function]
    main: list[Stmt]
    name: str = ""
    secondary: bool = False
    wrapped: bool = False  # main is the call of the one program def: it runs with the globals
