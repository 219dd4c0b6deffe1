"""URScript's checker: what the controller's compiler refuses before a program runs.

Every called name must be a function or thread of the program or a built-in the emulator
implements (`compile_error_name_not_found:NAME:` otherwise), `run` must name a thread, and a
user function's arguments must fit its parameters (by position, then by name), a built-in's the
parameters spec/urscript lists (no more of them, none twice). A method call
(`proxy.getTarget()`) is a remote procedure call: its name is the server's to know. It also
marks each expression that may call a user function (`Expr.user`): those the interpreter
evaluates step by step, since the function may wait (ur_rtde's `keep_running = process_cmd(cmd)`
runs a movej inside an expression).
"""

from __future__ import annotations

from collections.abc import Collection
from functools import cache

from rtde_spec.emulator.urscript.nodes import Expr, Function, Script, ScriptFault, Stmt


def check(script: Script, builtins: Collection[str], waits: Collection[str] = ()) -> None:
    """Raise the first compile error of `script`, in program order. `waits`: built-ins that may
    wait (motions, sleep, sync), marked as a user call is."""
    checker = _Checker(script, builtins, waits)
    checker.waiting = _waiting_functions(script, waits)
    for body in [script.main, *(f.body for f in script.functions.values())]:
        checker.body(body)


def check_added(
    functions: dict[str, Function], added: Script, builtins: Collection[str], waits: Collection[str]
) -> None:
    """Raise the first compile error of statements and functions `added` to a running program whose
    functions are `functions` (interpreter mode links them in): checked as one program would be."""
    merged = Script({**functions, **added.functions}, added.main)
    checker = _Checker(merged, builtins, waits)
    checker.waiting = _waiting_functions(merged, waits)
    for body in [added.main, *(f.body for f in added.functions.values())]:
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
            elif expr.kind == "method":  # a remote procedure call waits for its server
                direct = True
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
                _arguments_fit(function, expr, where)
                user = user or expr.value in self.waiting
            elif expr.value not in self.builtins:
                raise ScriptFault.name_not_found(expr.value, where, expr.column)
            else:
                _builtin_arguments_fit(expr, where)
                user = user or expr.value in self.waits
        elif expr.kind == "method":  # proxy.name(...): a remote procedure call, answered by its server
            user = True
        elif expr.kind == "run":
            function = self.functions.get(expr.value)
            if function is None or not function.thread:
                raise ScriptFault.name_not_found(expr.value, where, expr.column)
        expr.user = user
        return user


@cache
def _signatures() -> dict[str, list[str]]:
    """The built-ins' parameter names, in order (spec/urscript)."""
    from rtde_spec.metamodel.urscript import urscript_functions

    free = ("struct", "textmsg")  # struct's fields have any names; the emulator's textmsg joins any number
    return {f.name: [p.name for p in f.params] for f in urscript_functions().functions if f.name not in free}


def _builtin_arguments_fit(expr: Expr, line: int) -> None:
    """A built-in's call: no more arguments in order than it has parameters, none given twice (one
    it needs and is not given is the call's runtime exception). A name it does not have is let be:
    UR's own client library calls get_mass_matrix(include_rotor_inertia=...), the editions on hand
    name it include_rotors_inertia, and whether a controller refuses either is not known."""
    params = _signatures().get(str(expr.value))
    if params is None:
        return
    given, named = len(expr.items), [name for name, _ in expr.kwargs]
    twice = [n for i, n in enumerate(named) if n in params[:given] or n in named[:i]]
    what = (
        f"{twice[0]} given twice" if twice
        else f"takes at most {len(params)} arguments, got {given}" if given > len(params)
        else ""
    )  # fmt: skip
    if what:
        raise ScriptFault(f"compile_error: {expr.value} {what}", line, expr.column)


def _arguments_fit(function: Function, expr: Expr, line: int) -> None:
    """A user function's call: at most its parameters by position, then any of the rest by name
    (`f(1, b=2)`), each once, and every parameter without a default given one way or the other."""
    params = function.params
    given = len(expr.items)
    named = [name for name, _ in expr.kwargs]
    unknown = [n for n in named if n not in params]
    twice = [n for i, n in enumerate(named) if n in params[:given] or n in named[:i]]
    rest = zip(params[given:], function.defaults[given:], strict=True)
    missing = [p for p, default in rest if default is None and p not in named]
    what = (
        f"no parameter {unknown[0]}" if unknown
        else f"{twice[0]} given twice" if twice
        else f"takes {len(params)} arguments, got {given}" if given > len(params) or missing
        else ""
    )  # fmt: skip
    if what:
        raise ScriptFault(f"compile_error: {expr.value} {what}", line, expr.column)
