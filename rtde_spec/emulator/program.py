"""Run a parsed URScript program step by step, as the controller's interpreter does.

The program is a generator: each control step it runs statements until one must
wait (a motion, sleep, sync), then yields. Names are checked before anything runs,
as the controller compiles first. A fault at run time stops the program and
becomes a runtime exception event with the line; nothing is dropped silently.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Any

from rtde_spec.emulator import script_calls
from rtde_spec.emulator.events import ScriptEvent
from rtde_spec.emulator.interfaces import Robot, Wait
from rtde_spec.emulator.motion import MotionError
from rtde_spec.emulator.urscript import Expr, Function, Script, ScriptFault, Stmt
from rtde_spec.errors import RtdeSpecError


class Program:
    """One running program; `advance(dt)` once per control step (dt in s of real time)."""

    def __init__(self, script: Script, robot: Robot) -> None:
        self.script, self.robot = script, robot
        self.name = script.name or "script"
        self.applied: list[str] = []  # the I/O calls run, as written
        self.clock = 0.0
        self.finished = False
        self.fault: ScriptFault | None = None
        check_names(script)
        self._steps: Iterator[None] = self._run()

    def advance(self, dt: float = 0.0) -> None:
        if self.finished:
            return
        self.clock += dt
        try:
            next(self._steps)
        except StopIteration:
            self.finished = True
        except ScriptFault as fault:
            self.fail(fault)

    def fail(self, fault: ScriptFault) -> None:
        self.finished, self.fault = True, fault
        self.robot.emit(
            ScriptEvent("runtime_exception", fault.text, fault.line, fault.column, program=self.name)
        )

    def _run(self) -> Wait:
        yield from self._block(self.script.main, {})

    def _block(self, body: list[Stmt], scope: dict[str, Any]) -> Wait:
        for i, stmt in enumerate(body):
            following = body[i + 1] if i + 1 < len(body) else None
            try:
                yield from self._statement(stmt, scope, following)
            except ScriptFault:
                raise
            except MotionError as exc:
                raise ScriptFault(str(exc), stmt.line, 1) from exc
            except RtdeSpecError as exc:
                raise ScriptFault(exc.reason, stmt.line, 1) from exc

    def _statement(self, stmt: Stmt, scope: dict[str, Any], following: Stmt | None) -> Wait:
        assert stmt.expr is not None
        if stmt.kind == "assign":
            scope[stmt.name] = self.evaluate(stmt.expr, scope, stmt.line)
            return
        function = self.script.functions.get(stmt.name)
        if function is not None:
            yield from self._call(function, stmt, scope)
            return
        args = [self.evaluate(e, scope, stmt.line) for e in stmt.expr.items]
        kwargs = {k: self.evaluate(e, scope, stmt.line) for k, e in stmt.expr.kwargs}
        command = script_calls.COMMANDS.get(stmt.name)
        if command is not None:
            wait = command(self, stmt, args, kwargs)
            if wait is not None:
                yield from wait(blends_into_move(following))
            return
        script_calls.call_function(self, stmt, stmt.name, args, kwargs)  # a value nobody keeps

    def _call(self, function: Function, stmt: Stmt, scope: dict[str, Any]) -> Wait:
        assert stmt.expr is not None
        args = [self.evaluate(e, scope, stmt.line) for e in stmt.expr.items]
        if len(args) != len(function.params):
            raise ScriptFault(
                f"{function.name} takes {len(function.params)} arguments, got {len(args)}", stmt.line, 1
            )
        inner = {**scope, **dict(zip(function.params, args, strict=True))}
        yield from self._block(function.body, inner)

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
        if kind == "binop":
            left, right = (self.evaluate(e, scope, line) for e in expr.items)
            return script_calls.arithmetic(expr.value, left, right, line, expr.column)
        args = [self.evaluate(e, scope, line) for e in expr.items]
        kwargs = {k: self.evaluate(e, scope, line) for k, e in expr.kwargs}
        stmt = Stmt("call", line, "", expr.value, expr)
        return script_calls.call_function(self, stmt, expr.value, args, kwargs)

    def wait_for(self, done: Callable[[], bool]) -> Wait:
        while not done():
            yield


def blends_into_move(stmt: Stmt | None) -> bool:
    return stmt is not None and stmt.kind == "call" and stmt.name in script_calls.MOVES


def check_names(script: Script) -> None:
    """Every called name exists (a function of the script or one the emulator runs), before any runs."""
    known = set(script.functions) | set(script_calls.COMMANDS) | set(script_calls.FUNCTIONS)
    bodies = [script.main, *(f.body for f in script.functions.values())]
    for body in bodies:
        for stmt in body:
            if stmt.expr is not None:
                _check_expr(stmt.expr, known, stmt.line)


def _check_expr(expr: Expr, known: set[str], line: int) -> None:
    if expr.kind == "call" and expr.value not in known:
        raise ScriptFault(f"compile_error_name_not_found:{expr.value}", line, expr.column)
    for item in (*expr.items, *(e for _, e in expr.kwargs)):
        _check_expr(item, known, line)
