"""Run a parsed URScript program step by step, as the controller's interpreter does.

The program is a generator: each control step it runs statements until one must
wait (a motion, sleep, sync), then yields. Names are checked before anything runs,
as the controller compiles first. `if`/`elif`/`else` and `while` run their bodies
in the enclosing scope; `break`, `continue` and `return` travel up as the value a
body's generator returns. A program may run STEP_BUDGET statements in one control
step; a loop that runs more without waiting is the controller's "Runtime is too
much behind" fault, so it can never hang the control step. A fault at run time
stops the program and becomes a runtime exception event with the line; nothing is
dropped silently.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator, Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any

from rtde_spec.emulator import script_calls, urscript_ops
from rtde_spec.emulator.events import ScriptEvent
from rtde_spec.emulator.interfaces import Robot, Wait
from rtde_spec.emulator.motion import MotionError
from rtde_spec.emulator.urscript import Branch, Expr, Function, Script, ScriptFault, Stmt
from rtde_spec.errors import RtdeSpecError

PROGRAM_ERRORS = (ArithmeticError, ValueError, TypeError, IndexError, KeyError, RecursionError, MemoryError)
"""What a statement's Python may raise on a program's values (huge numbers, deep nesting): the
program's runtime exception, never the end of the emulator's control loop."""

STEP_BUDGET = 10_000  # statements (and loop turns) one control step may run without waiting
MAX_CALL_DEPTH = 64  # user functions calling user functions; deeper is a runaway recursion


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


class _Flow(Enum):
    BREAK = "break"
    CONTINUE = "continue"


@dataclass(frozen=True)
class _Return:
    value: Any


Signal = _Flow | _Return | None
Steps = Generator[None, None, Signal]


@dataclass(eq=False)  # told apart by identity: a recursion runs one loop twice
class _Loop:
    stmt: Stmt
    epoch: int  # the control step of its latest turn


class _WaitsInExpression(Exception):
    """A waiting call reached from a function called in an expression (which cannot wait)."""

    def __init__(self, stmt: Stmt) -> None:
        super().__init__(stmt.name)
        self.stmt = stmt


class Program:
    """One running program; `advance(dt)` once per control step (dt in s of real time)."""

    def __init__(self, script: Script, robot: Robot) -> None:
        self.script, self.robot = script, robot
        self.name = script.name or "script"
        self.applied: list[str] = []  # the I/O calls run, as written
        self.clock = 0.0
        self.finished = False
        self.fault: ScriptFault | None = None
        self._ran = 0  # statements since the program last waited
        self._epoch = 0  # control steps advanced
        self._loops: list[_Loop] = []  # the while loops running, outermost first
        self._depth = 0  # user-function calls running
        self._in_expression = 0  # user-function calls made from expressions, running
        check_names(script)
        self._steps: Iterator[None] = self._run()

    def advance(self, dt: float = 0.0) -> None:
        if self.finished:
            return
        self.clock += dt
        self._ran, self._epoch = 0, self._epoch + 1
        try:
            next(self._steps)
        except StopIteration:
            self.finished = True
        except ScriptFault as fault:
            self.fail(fault)
        except PROGRAM_ERRORS as exc:  # out of no statement (resuming a chain nested past the limit)
            self.fail(ScriptFault(runtime_text(exc), 0, 0))

    def fail(self, fault: ScriptFault) -> None:
        self.finished, self.fault = True, fault
        self.robot.emit(
            ScriptEvent("runtime_exception", fault.text, fault.line, fault.column, program=self.name)
        )

    def _run(self) -> Wait:
        yield from self._block(self.script.main, {})

    def _block(self, body: list[Stmt], scope: dict[str, Any]) -> Steps:
        for i, stmt in enumerate(body):
            following = body[i + 1] if i + 1 < len(body) else None
            self._count(stmt)
            try:
                signal = yield from self._statement(stmt, scope, following)
            except ScriptFault:
                raise
            except MotionError as exc:
                raise ScriptFault(str(exc), stmt.line, 1) from exc
            except RtdeSpecError as exc:
                raise ScriptFault(exc.reason, stmt.line, 1) from exc
            except PROGRAM_ERRORS as exc:  # whatever a program does, it faults; the control step goes on
                raise ScriptFault(runtime_text(exc), stmt.line, 1) from None
            if signal is not None:
                return signal
        return None

    def _count(self, stmt: Stmt) -> None:
        """One more statement without a wait; past the budget, the loop that never waits faults."""
        self._ran += 1
        if self._ran <= STEP_BUDGET:
            return
        loop = next((loop.stmt for loop in self._loops if loop.epoch == self._epoch), stmt)
        raise ScriptFault(
            f"Runtime is too much behind: the loop on line {loop.line} did not yield "
            f"({STEP_BUDGET} statements in one control step); add sync() or sleep() to it",
            loop.line,
            1,
        )

    def _statement(self, stmt: Stmt, scope: dict[str, Any], following: Stmt | None) -> Steps:
        kind = stmt.kind
        if kind == "assign":
            self._assign(stmt, scope)
            return None
        if kind == "if":
            for branch in stmt.branches:
                if branch.cond is None or self._condition(branch, scope):
                    return (yield from self._block(branch.body, scope))
            return None
        if kind == "while":
            return (yield from self._while(stmt, scope))
        if kind in ("break", "continue"):
            return _Flow(kind)
        if kind == "return":
            return _Return(self.evaluate(stmt.expr, scope, stmt.line) if stmt.expr is not None else None)
        assert stmt.expr is not None
        function = self.script.functions.get(stmt.name)
        if function is not None:
            args = [self.evaluate(e, scope, stmt.line) for e in stmt.expr.items]
            yield from self._invoke(function, args, scope, stmt.line, stmt.expr.column)
            return None
        args = [self.evaluate(e, scope, stmt.line) for e in stmt.expr.items]
        kwargs = {k: self.evaluate(e, scope, stmt.line) for k, e in stmt.expr.kwargs}
        command = script_calls.COMMANDS.get(stmt.name)
        if command is not None:
            if self._in_expression and stmt.name in script_calls.WAITS:
                raise _WaitsInExpression(stmt)  # before the motion starts: nothing half done
            wait = command(self, stmt, args, kwargs)
            if wait is not None:
                yield from wait(blends_into_move(following))
            return None
        script_calls.call_function(self, stmt, stmt.name, args, kwargs)  # a value nobody keeps
        return None

    def _while(self, stmt: Stmt, scope: dict[str, Any]) -> Steps:
        branch = stmt.branches[0]
        loop = _Loop(stmt, self._epoch)
        self._loops.append(loop)
        try:
            while True:
                loop.epoch = self._epoch
                self._count(stmt)  # a turn counts, so even an empty body cannot spin forever
                if not self._condition(branch, scope):
                    return None
                signal = yield from self._block(branch.body, scope)
                if signal is _Flow.BREAK:
                    return None
                if isinstance(signal, _Return):
                    return signal
        finally:
            self._loops.remove(loop)

    def _condition(self, branch: Branch, scope: dict[str, Any]) -> bool:
        assert branch.cond is not None
        value = self.evaluate(branch.cond, scope, branch.line)
        return urscript_ops.truth(value, "a condition", branch.line, branch.column)

    def _assign(self, stmt: Stmt, scope: dict[str, Any]) -> None:
        assert stmt.expr is not None
        value = self.evaluate(stmt.expr, scope, stmt.line)
        if not stmt.index:
            scope[stmt.name] = value
            return
        if stmt.name not in scope:
            raise ScriptFault(f"compile_error_name_not_found:{stmt.name}", stmt.line, stmt.column)
        positions = [self.evaluate(e, scope, stmt.line) for e in stmt.index]
        scope[stmt.name] = urscript_ops.replaced(scope[stmt.name], positions, value, stmt.line, stmt.column)

    def _invoke(
        self, function: Function, args: list[Any], scope: Mapping[str, Any], line: int, column: int
    ) -> Steps:
        if len(args) != len(function.params):
            raise ScriptFault(
                f"{function.name} takes {len(function.params)} arguments, got {len(args)}", line, column or 1
            )
        if self._depth >= MAX_CALL_DEPTH:
            raise ScriptFault(f"{function.name}: calls nested deeper than {MAX_CALL_DEPTH}", line, column)
        inner = {**scope, **dict(zip(function.params, args, strict=True))}
        self._depth += 1
        try:
            return (yield from self._block(function.body, inner))
        finally:
            self._depth -= 1

    def _call_in_expression(
        self, function: Function, args: list[Any], scope: Mapping[str, Any], line: int, column: int
    ) -> Any:
        """Run a user function to its end at once: an expression's value cannot wait for a step."""
        self._in_expression += 1
        steps = self._invoke(function, args, scope, line, column)
        try:
            next(steps)
        except StopIteration as done:
            result = done.value
        except _WaitsInExpression as exc:
            raise ScriptFault(
                f"{function.name}() waits ({exc.stmt.name} on line {exc.stmt.line}), "
                "so it cannot be called in an expression; call it as a statement",
                line,
                column,
            ) from None
        else:  # only halt's wait gets here, and it is refused before; kept for safety
            steps.close()
            raise ScriptFault(f"{function.name}() waits: not in an expression", line, column)
        finally:
            self._in_expression -= 1
        if not isinstance(result, _Return) or result.value is None:
            raise ScriptFault(f"{function.name}() returns no value", line, column)
        return result.value

    def evaluate(self, expr: Expr, scope: Mapping[str, Any], line: int) -> Any:
        kind = expr.kind
        if kind in ("num", "str", "bool"):
            return expr.value
        if kind == "name":
            if expr.value in scope:
                return scope[expr.value]
            if expr.value in script_calls.CONSTANTS:
                return script_calls.CONSTANTS[expr.value]
            raise ScriptFault(f"compile_error_name_not_found:{expr.value}", line, expr.column)
        if kind == "list":
            return [self.evaluate(e, scope, line) for e in expr.items]
        if kind == "pose":
            return script_calls.make_pose(
                [self.evaluate(e, scope, line) for e in expr.items], line, expr.column
            )
        if kind == "neg":
            return script_calls.arithmetic(
                "-", 0, self.evaluate(expr.items[0], scope, line), line, expr.column
            )
        if kind in ("logic", "not"):
            return self._logic(expr, scope, line)
        if kind in ("binop", "compare", "index"):
            left, right = (self.evaluate(e, scope, line) for e in expr.items)
            if kind == "compare":
                return urscript_ops.compare(expr.value, left, right, line, expr.column)
            if kind == "index":
                return urscript_ops.index(left, right, line, expr.column)
            return script_calls.arithmetic(expr.value, left, right, line, expr.column)
        args = [self.evaluate(e, scope, line) for e in expr.items]
        function = self.script.functions.get(expr.value)
        if function is not None:
            return self._call_in_expression(function, args, scope, line, expr.column)
        kwargs = {k: self.evaluate(e, scope, line) for k, e in expr.kwargs}
        stmt = Stmt("call", line, "", expr.value, expr)
        return script_calls.call_function(self, stmt, expr.value, args, kwargs)

    def _logic(self, expr: Expr, scope: Mapping[str, Any], line: int) -> bool:
        """`not`, `and`, `or`, `xor` on bools; `and`/`or` skip the right side when the left decides."""
        word = expr.value or "not"

        def operand(item: Expr) -> bool:
            value = self.evaluate(item, scope, line)
            return urscript_ops.truth(value, f"{word}'s operand", line, item.column)

        left = operand(expr.items[0])
        if word == "not":
            return not left
        if (word == "and" and not left) or (word == "or" and left):
            return left
        right = operand(expr.items[1])
        return left != right if word == "xor" else right

    def wait_for(self, done: Callable[[], bool]) -> Wait:
        while not done():
            yield


def blends_into_move(stmt: Stmt | None) -> bool:
    return stmt is not None and stmt.kind == "call" and stmt.name in script_calls.MOVES


def check_names(script: Script) -> None:
    """Every called name exists (a function of the script or one the emulator runs), before any runs."""
    known = set(script.functions) | set(script_calls.COMMANDS) | set(script_calls.FUNCTIONS)
    for body in [script.main, *(f.body for f in script.functions.values())]:
        _check_body(body, known)


def _check_body(body: list[Stmt], known: set[str]) -> None:
    for stmt in body:
        for expr in (stmt.expr, *stmt.index):
            if expr is not None:
                _check_expr(expr, known, stmt.line)
        for branch in stmt.branches:
            if branch.cond is not None:
                _check_expr(branch.cond, known, branch.line)
            _check_body(branch.body, known)


def _check_expr(expr: Expr, known: set[str], line: int) -> None:
    if expr.kind == "call" and expr.value not in known:
        raise ScriptFault(f"compile_error_name_not_found:{expr.value}", line, expr.column)
    for item in (*expr.items, *(e for _, e in expr.kwargs)):
        _check_expr(item, known, line)
