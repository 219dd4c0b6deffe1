"""URScript's checker: what the controller's compiler refuses before a program runs.

Every called name must be a function or thread of the program or a built-in the emulator
implements (`compile_error_name_not_found:NAME` otherwise), `run` must name a thread, and a
user function's arguments must fit its parameters. It also marks each expression that may call
a user function (`Expr.user`): those the interpreter evaluates step by step, since the function
may wait (ur_rtde's `keep_running = process_cmd(cmd)` runs a movej inside an expression).
"""

from __future__ import annotations

from collections.abc import Collection

from rtde_spec.emulator.urscript.nodes import Expr, Script, ScriptFault, Stmt


def check(script: Script, builtins: Collection[str], waits: Collection[str] = ()) -> None:
    """Raise the first compile error of `script`, in program order. `waits`: built-ins that may
    wait (motions, sleep, sync), marked as a user call is."""
    checker = _Checker(script, builtins, waits)
    checker.waiting = _waiting_functions(script, waits)
    for body in [script.main, *(f.body for f in script.functions.values())]:
        checker.body(body)


def _waiting_functions(script: Script, waits: Collection[str]) -> set[str]:
    """The user functions that may wait: calling a waiting built-in, join, halt, or one of these."""
    calls: dict[str, set[str]] = {}
    waiting: set[str] = set()
    for name, function in script.functions.items():
        found: set[str] = set()
        if _walk(function.body, found, waits):
            waiting.add(name)
        calls[name] = found
    changed = True
    while changed:  # to a fixed point over the call graph: linear in functions x rounds
        changed = False
        for name, called in calls.items():
            if name not in waiting and called & waiting:
                waiting.add(name)
                changed = True
    return waiting


def _walk(body: list[Stmt], found: set[str], waits: Collection[str]) -> bool:
    """Collect the names `body` calls into `found`; True if it calls a waiting built-in itself."""
    direct = False
    for stmt in body:
        if stmt.kind in ("join", "halt"):
            direct = True
        exprs = [stmt.expr, *stmt.index, *(b.cond for b in stmt.branches)]
        stack = [e for e in exprs if e is not None]
        while stack:
            expr = stack.pop()
            if expr.kind == "call":
                found.add(expr.value)
                direct = direct or expr.value in waits
            stack.extend(expr.items)
            stack.extend(e for _, e in expr.kwargs)
        for branch in stmt.branches:
            direct = _walk(branch.body, found, waits) or direct
    return direct


class _Checker:
    def __init__(self, script: Script, builtins: Collection[str], waits: Collection[str]) -> None:
        self.functions = script.functions
        self.builtins = builtins
        self.waits = waits
        self.waiting: set[str] = set()  # user functions that may wait

    def body(self, body: list[Stmt]) -> None:
        for stmt in body:
            for expr in (stmt.expr, *stmt.index):
                if expr is not None:
                    self.expr(expr, stmt.line)
            for branch in stmt.branches:
                if branch.cond is not None:
                    self.expr(branch.cond, branch.line)
                self.body(branch.body)

    def expr(self, expr: Expr, line: int) -> bool:
        """Check `expr` and everything in it; True (and marked) if evaluating it may wait."""
        user = False
        for item in expr.items:
            user = self.expr(item, line) or user
        for _, item in expr.kwargs:
            user = self.expr(item, line) or user
        where = expr.line or line
        if expr.kind == "call":
            function = self.functions.get(expr.value)
            if function is not None and not function.thread:
                given = len(expr.items)
                required = sum(1 for d in function.defaults if d is None)
                if not required <= given <= len(function.params) or expr.kwargs:
                    raise ScriptFault(
                        f"compile_error: {expr.value} takes {len(function.params)} arguments, got {given}",
                        where,
                        expr.column,
                    )
                user = user or expr.value in self.waiting
            elif expr.value not in self.builtins:
                raise ScriptFault(f"compile_error_name_not_found:{expr.value}", where, expr.column)
            else:
                user = user or expr.value in self.waits
        elif expr.kind == "run":
            function = self.functions.get(expr.value)
            if function is None or not function.thread:
                raise ScriptFault(f"compile_error_name_not_found:{expr.value}", where, expr.column)
        expr.user = user
        return user
