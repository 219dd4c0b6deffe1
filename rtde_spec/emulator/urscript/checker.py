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
    for body in [script.main, *(f.body for f in script.functions.values())]:
        checker.body(body)


class _Checker:
    def __init__(self, script: Script, builtins: Collection[str], waits: Collection[str]) -> None:
        self.functions = script.functions
        self.builtins = builtins
        self.waits = waits

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
        """Check `expr` and everything in it; True (and marked) if it may call a user function."""
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
                user = True
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
