"""URScript expressions, calls and assignments: the values half of the interpreter.

`value` evaluates an expression that cannot wait at once; `steps` evaluates one that may call
a user function (the checker marked it) as a generator the thread steps through, so a function
that moves the arm can still give a value. Values keep URScript's shapes: lists nest at most
MAX_NESTING deep (a matrix of poses), so no value a program builds can make a comparison or
`norm` run for minutes or take gigabytes.
"""

from __future__ import annotations

import operator
import time
from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rtde_spec.emulator.urscript import builtins, matrices, rpc
from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript import values as urscript_ops
from rtde_spec.emulator.urscript.interfaces import Robot
from rtde_spec.emulator.urscript.lookahead import blends_into_move
from rtde_spec.emulator.urscript.nodes import Branch, Expr, Function, Script, ScriptFault, Stmt

if TYPE_CHECKING:
    from rtde_spec.emulator.urscript.interfaces import Wait

Frame = dict[str, Any]
MAX_CALL_DEPTH = 64  # user functions calling user functions; deeper is a runaway recursion
MAX_NESTING = 3  # lists in lists in lists (an array of poses is 2)
MAX_ELEMENTS = matrices.MAX_ELEMENTS  # elements of one value, through its lists (one held twice counts twice)
MANY = 256  # items of one list or call between looks at the statement's CPU time
STATEMENT_SECONDS = 0.004  # CPU one statement's list or arguments may take (two e-Series steps)


_NUMBERS = (int, float)  # exact types: a bool is no number here
_COMPARE: dict[str, Callable[[Any, Any], bool]] = {
    "==": operator.eq, "!=": operator.ne, "<": operator.lt,
    "<=": operator.le, ">": operator.gt, ">=": operator.ge,
}  # fmt: skip


_NONE: dict[str, Any] = {}  # no keyword arguments (never changed: builtins only read it)


@dataclass(frozen=True)
class Return:
    value: Any


Steps = Generator[None, None, Any]


def runtime_text(exc: BaseException) -> str:
    """The runtime exception's text for a Python error a program's values caused."""
    if isinstance(exc, RecursionError):
        return "the program nests too deeply (calls, blocks or values)"
    if isinstance(exc, ZeroDivisionError):
        return "Division by zero"
    if isinstance(exc, OverflowError):
        return "Number too large"
    if isinstance(exc, MemoryError):
        return "out of memory"
    return f"runtime error: {exc}"[:200]


def shape(items: list[Any]) -> tuple[int, int]:
    """How deep a new list of `items` nests and how many elements it holds through its lists.

    A list held twice counts twice but is walked once, and the walk stops past MAX_ELEMENTS,
    so this costs at most about MAX_ELEMENTS steps whatever the value shares."""
    seen: dict[int, tuple[int, int]] = {}

    def walk(values: list[Any]) -> tuple[int, int]:
        known = seen.get(id(values))
        if known is not None:
            return known
        inner = [v for v in values if isinstance(v, list)]
        deepest, count = 0, len(values) - len(inner)
        for item in inner:
            depth, size = walk(item)
            deepest, count = max(deepest, depth), count + size
            if count > MAX_ELEMENTS:
                break
        seen[id(values)] = (deepest + 1, count)
        return deepest + 1, count

    return walk(items)


def check_shape(values: list[Any], line: int, column: int) -> None:
    """A list value a program builds: at most MAX_NESTING deep, MAX_ELEMENTS elements."""
    depth, count = shape(values)
    if depth > MAX_NESTING:
        raise ScriptFault(f"Type error: arrays nest at most {MAX_NESTING} deep", line, column)
    if count > MAX_ELEMENTS:
        raise ScriptFault(f"Type error: an array holds at most {MAX_ELEMENTS} elements", line, column)


class Evaluator:
    """Expressions and calls of a program; the interpreter adds statements and threads."""

    current: Any  # the interpreter's running thread (its id and name)
    threads: dict[int, Any]  # the interpreter's live threads, by handle

    def __init__(self, script: Script, robot: Robot) -> None:
        self.script, self.robot = script, robot
        self.globals: Frame = {}
        self._depth = 0
        self._sync = 0  # > 0 while a function runs inside an expression (it cannot be preempted)
        self.labels: dict[int, tuple[str, int, str]] = {}  # thread id -> (its name, last `$` label)

    # the interpreter's side
    def block(self, body: list[Stmt], frame: Frame) -> Steps:
        raise NotImplementedError

    def start_thread(self, name: str, line: int, column: int) -> int:
        raise NotImplementedError

    def wait_for(self, done: Any) -> Wait:
        raise NotImplementedError

    @staticmethod
    def over_budget(began: float, line: int) -> None:
        """The controller's runtime error once one statement's items took STATEMENT_SECONDS of CPU."""
        if time.thread_time() - began > STATEMENT_SECONDS:
            raise ScriptFault(
                f"Runtime is too much behind: line {line} took over {STATEMENT_SECONDS * 1000:g} ms "
                "in one control step",
                line,
                1,
            )

    # --- names --------------------------------------------------------------------------------

    def lookup(self, expr: Expr, frame: Frame) -> Any:
        name = expr.value
        if name in frame:
            return frame[name]
        if name in self.globals:
            return self.globals[name]
        if name in script_calls.CONSTANTS:
            return script_calls.CONSTANTS[name]
        raise ScriptFault.name_not_found(name, expr.line, expr.column)

    def assign(self, stmt: Stmt, frame: Frame, value: Any) -> None:
        name = stmt.name
        if stmt.scope == "global":
            where = self.globals
        elif stmt.scope == "local" or name in frame or name not in self.globals:
            where = frame
        else:
            where = self.globals
        if not stmt.index:
            where[name] = value
            return
        if name not in where:
            raise ScriptFault.name_not_found(name, stmt.line, stmt.column)
        positions = [
            urscript_ops.Member(e.value)
            if e.kind == "member"
            else self.value(e, frame)
            if e.kind != "pair"
            else tuple(self.value(i, frame) for i in e.items)
            for e in stmt.index
        ]  # a matrix's row and column are one subscript, a tuple; a struct's field a Member
        changed = urscript_ops.replaced(where[name], positions, value, stmt.line, stmt.column)
        if isinstance(value, list):  # `a[0] = a` must not nest a value deeper each turn
            check_shape(changed, stmt.line, stmt.column)
        where[name] = changed

    def condition(self, branch: Branch, frame: Frame) -> Steps:
        assert branch.cond is not None
        cond = branch.cond
        value = self.value(cond, frame) if not cond.user else (yield from self.steps(cond, frame))
        return urscript_ops.condition(value, branch.line, branch.column)

    # --- expressions --------------------------------------------------------------------------

    def value(self, expr: Expr, frame: Frame) -> Any:
        kind = expr.kind
        if kind in ("num", "str", "bool"):
            return expr.value
        if kind == "name":
            name = expr.value
            if name in frame:
                return frame[name]
            return self.lookup(expr, frame)
        if kind == "compare":  # numbers compare at once; anything else goes through the type checks
            left, right = self.value(expr.items[0], frame), self.value(expr.items[1], frame)
            if type(left) in _NUMBERS and type(right) in _NUMBERS:
                return _COMPARE[expr.value](left, right)
            return urscript_ops.compare(expr.value, left, right, expr.line, expr.column)
        if kind in ("logic", "not"):
            left = self.value(expr.items[0], frame)
            if type(left) is not bool:
                left = self._operand(left, expr, 0)  # the type error
            if kind == "not":
                return not left
            word = expr.value
            if (word == "and" and not left) or (word == "or" and left):
                return left
            right = self.value(expr.items[1], frame)
            if type(right) is not bool:
                right = self._operand(right, expr, 1)
            return left != right if word == "xor" else right
        if kind == "pose" and len(expr.items) < 3 and ("p" in frame or "p" in self.globals):
            variable = frame["p"] if "p" in frame else self.globals["p"]  # `p[0]` of a variable named p
            at = [self.value(e, frame) for e in expr.items]
            if len(at) == 2:
                return matrices.cell(variable, at[0], at[1], expr.line, expr.column)
            return urscript_ops.index(variable, at[0], expr.line, expr.column)
        if kind == "run":
            return self.start_thread(expr.value, expr.line, expr.column)
        items = expr.items
        if len(items) > MANY:
            values = self._many(items, frame, expr.line)
        else:
            values = [self.value(e, frame) for e in items]
        kwargs = {k: self.value(e, frame) for k, e in expr.kwargs} if expr.kwargs else _NONE
        return self.combine(expr, values, kwargs)

    def _many(self, items: tuple[Expr, ...], frame: Frame, line: int) -> list[Any]:
        """The values of a long list or argument list, within the step's CPU budget."""
        values: list[Any] = []
        began = time.thread_time()
        for start in range(0, len(items), MANY):
            self.over_budget(began, line)
            values.extend([self.value(e, frame) for e in items[start : start + MANY]])
        return values

    def steps(self, expr: Expr, frame: Frame) -> Steps:
        """`value`, for an expression that may wait: yields while a function it calls waits."""
        if not expr.user:
            return self.value(expr, frame)
        kind = expr.kind
        if kind in ("logic", "not"):
            left = self._operand((yield from self.steps(expr.items[0], frame)), expr, 0)
            if kind == "not":
                return not left
            word = expr.value
            if (word == "and" and not left) or (word == "or" and left):
                return left
            right = self._operand((yield from self.steps(expr.items[1], frame)), expr, 1)
            return left != right if word == "xor" else right
        values, kwargs = yield from self.arguments(expr, frame)
        if kind == "method":  # proxy.name(args): the server's answer, waited for
            result = yield from rpc.call(expr, values[0], values[1:], kwargs)
            if isinstance(result, list):
                check_shape(result, expr.line, expr.column)
            return result
        if kind == "call":
            function = self.script.functions.get(expr.value)
            if function is not None:
                result = yield from self.invoke(function, values, expr, kwargs)
                return result.value if isinstance(result, Return) else None
            waiting = builtins.WAITING.get(expr.value)
            if waiting is not None:
                stmt = Stmt("call", expr.line, "", expr.value, expr, expr.column)
                return (yield from waiting(self, stmt, values, kwargs))  # type: ignore[arg-type]
            command = script_calls.COMMANDS.get(expr.value)
            if command is not None:
                stmt = Stmt("call", expr.line, "", expr.value, expr, expr.column)
                wait = command(self, stmt, values, kwargs)  # type: ignore[arg-type]
                if wait is not None:
                    yield from wait(False)
                return None
        return self.combine(expr, values, kwargs)

    def thread_labels(self) -> list[tuple[str, int, str]]:
        """(thread name, label number, label text) of each running thread that passed a label."""
        return [label for key, label in self.labels.items() if key in self.threads]

    def arguments(self, expr: Expr, frame: Frame) -> Generator[None, None, tuple[list[Any], dict[str, Any]]]:
        values: list[Any] = []
        began = time.thread_time()
        for i, item in enumerate(expr.items):
            if i and not i % MANY:
                self.over_budget(began, expr.line)
            values.append((yield from self.steps(item, frame)))
        kwargs: dict[str, Any] = {}
        for key, item in expr.kwargs:
            kwargs[key] = yield from self.steps(item, frame)
        return values, kwargs

    def _operand(self, value: Any, expr: Expr, i: int) -> bool:
        item = expr.items[i]
        word = expr.value or "not"
        return urscript_ops.truth(value, f"{word}'s operand", item.line or expr.line, item.column)

    def combine(self, expr: Expr, values: list[Any], kwargs: dict[str, Any]) -> Any:
        kind, line, column = expr.kind, expr.line, expr.column
        if kind == "call":  # the commonest first
            function = self.script.functions.get(expr.value)
            if function is not None:  # one that never waits (the checker says): run to its end now
                steps = self.invoke(function, values, expr, kwargs)
                self._sync += 1  # it runs to its end here: no thread switch inside it
                try:
                    next(steps)
                except StopIteration as done:
                    return done.value.value if isinstance(done.value, Return) else None
                finally:
                    self._sync -= 1
                steps.close()
                raise ScriptFault(f"{expr.value}() waits: not in this expression", line, column)
            stmt = expr.call
            if stmt is None:
                stmt = expr.call = Stmt("call", line, "", expr.value, expr, column)
            return builtins.call(self, stmt, values, kwargs)  # type: ignore[arg-type]
        if kind == "binop":
            return script_calls.arithmetic(expr.value, values[0], values[1], line, column)
        if kind == "list":
            check_shape(values, line, column)
            return values
        if kind == "pose":
            return script_calls.make_pose(values, line, column)
        if kind == "neg":
            return script_calls.arithmetic("-", 0, values[0], line, column)
        if kind == "compare":
            return urscript_ops.compare(expr.value, values[0], values[1], line, column)
        if kind == "index":
            if len(values) == 3:  # m[i, j]
                return matrices.cell(values[0], values[1], values[2], line, column)
            return urscript_ops.index(values[0], values[1], line, column)
        if kind == "field":
            return builtins.field(values[0], expr.value, line, column)
        raise ScriptFault(f"syntax_error_on_line:{line}:", line, column)

    # --- calls --------------------------------------------------------------------------------

    def invoke(self, function: Function, args: list[Any], expr: Expr, kwargs: Frame = _NONE) -> Steps:
        """A user function's run; `kwargs` its parameters by name (URCaps call `RG2(target_width=110)`)."""
        if self._depth >= MAX_CALL_DEPTH:
            raise ScriptFault(
                f"{function.name}: calls nested deeper than {MAX_CALL_DEPTH}", expr.line, expr.column
            )
        params = function.params
        frame: Frame = dict(zip(params, args, strict=False))
        frame.update(kwargs)  # the checker allowed only parameters not given by position
        if len(frame) < len(params):
            for name, default in zip(params, function.defaults, strict=True):
                if name not in frame:
                    frame[name] = self.value(default, frame) if default is not None else None
        self._depth += 1
        try:
            return (yield from self.block(function.body, frame))
        finally:
            self._depth -= 1

    def call_now(self, stmt: Stmt, frame: Frame) -> None:
        """A call as a statement that cannot wait (the checker says): a user function, a command
        such as textmsg, or a function whose value nobody keeps."""
        expr = stmt.expr
        assert expr is not None
        items = expr.items
        values = (
            self._many(items, frame, expr.line)
            if len(items) > MANY
            else [self.value(e, frame) for e in items]
        )
        kwargs = {k: self.value(e, frame) for k, e in expr.kwargs}
        command = script_calls.COMMANDS.get(stmt.name)
        if command is not None and stmt.name not in self.script.functions:
            command(self, stmt, values, kwargs)  # type: ignore[arg-type]
            return
        if stmt.name in self.script.functions:
            self.combine(expr, values, kwargs)
            return
        builtins.call(self, stmt, values, kwargs)  # type: ignore[arg-type]

    def call_statement(self, stmt: Stmt, frame: Frame, following: Stmt | None) -> Steps:
        """A call as a statement: a user function, a command that may wait, or a value dropped
        (and a program label, `$ 3 "MoveJ"`: where the running thread is now)."""
        expr = stmt.expr
        assert expr is not None
        if stmt.kind == "label":
            self.labels[self.current.id] = (self.current.name, expr.value, stmt.name)
            return None
        if expr.kind == "run":
            return self.value(expr, frame)
        if expr.kind == "method":  # a remote procedure call whose answer nobody keeps
            yield from self.steps(expr, frame)
            return None
        values, kwargs = yield from self.arguments(expr, frame)
        function = self.script.functions.get(stmt.name)
        if function is not None:
            yield from self.invoke(function, values, expr, kwargs)
            return None
        command = script_calls.COMMANDS.get(stmt.name)
        if command is not None:
            wait = command(self, stmt, values, kwargs)  # type: ignore[arg-type]
            if wait is not None:
                yield from wait(blends_into_move(following))
            return None
        waiting = builtins.WAITING.get(stmt.name)
        if waiting is not None:
            yield from waiting(self, stmt, values, kwargs)  # type: ignore[arg-type]
            return None
        builtins.call(self, stmt, values, kwargs)  # type: ignore[arg-type]
        return None
