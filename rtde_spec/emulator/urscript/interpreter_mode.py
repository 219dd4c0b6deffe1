"""Interpreter mode (e-Series 5.10 on): statements a client sends on the interpreter socket (30020)
run in the program's main thread while it sits in `interpreter_mode()`.

As UR's Script Directory (e-Series, chapter 13 "Interpreter Mode") and its article "Interpreter
mode" describe it: each line received is one or more whole statements; while the program is in
interpreter mode each is compiled and linked into the running program (its functions join the
program's) and answered `ack: <id>: <statement>` with a consecutive id from 1, or `discard:
<reason>: <statement>` when it does not compile or no program runs. The statements run in order in
the scope `interpreter_mode()` was called from, taking the time they take (a movej moves the arm
as the program's own do). Lines sent while the program runs but is not in interpreter mode wait
in a queue, answered when it is entered (`clearQueueOnEnter=False`) or discarded then (True, the
default). A `clear_interpreter()` interpreted holds the lines after it unanswered until it ran.
`abort`, `skipbuffer` and the state commands (`statelastexecuted` ... `stateunexecuted`) are
answered at once, `state: <id>: <command>`. `end_interpreter()` makes `interpreter_mode()` return;
with `clearOnEnd` (the default) what it interpreted is cleared.

Where the documents say nothing the emulator decides (docs/decisions.md, and the reason texts here):
`skipbuffer` and `abort`, whose "return value should be ignored", answer in the state form with
the statements skipped and whether a move was aborted; a line that does not parse is a "Syntax
error", one the compiler refuses a "Compile error" (the reasons UR-facing clients match); a
runtime error in a statement faults the program as any statement's does; statements that never
wait run at most MAX_PER_STEP a control step.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rtde_spec.emulator.arm.motion import JointMove, LinearMove
from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript.checker import check_added
from rtde_spec.emulator.urscript.nodes import Expr, Script, ScriptFault, Stmt
from rtde_spec.emulator.urscript.parser import parse
from rtde_spec.emulator.urscript.registry import registrar
from rtde_spec.emulator.urscript.script_threads import close_thread
from rtde_spec.emulator.urscript.values import truth

if TYPE_CHECKING:
    from rtde_spec.emulator.urscript.interfaces import Runner

Program = Any  # interpreter.Program (which imports this module): its script, names, block, arguments

Reply = Callable[[str], None]
CONTROL = (
    "abort",
    "skipbuffer",
    "statelastexecuted",
    "statelastinterpreted",
    "statelastcleared",
    "stateunexecuted",
)
INVALID_STATE = "Program is in an invalid state"  # no program runs (the reason UR-facing clients match)
TOO_MANY = "Too many interpreted messages"
MAX_INTERPRETED = 5000  # statements one interpreter mode holds before clear_interpreter() (the emulator's)
MAX_PER_STEP = 100  # statements that never wait, run in one control step
MAX_QUEUED = 1000  # lines received and not yet interpreted (more are discarded)
MAX_LINE = 16 << 10  # characters of one line (compiling a longer one would hold up the control loop)
INTERPRET_SECONDS = 0.0005  # CPU a control step (or a batch of lines received) spends interpreting
TOO_LONG = "Statement too long"  # the emulator's own reason
IMODE: dict[str, Any] = {}  # the built-ins this module runs (builtins.py merges them)
_enter = registrar(IMODE)


@dataclass
class Received:
    text: str
    reply: Reply


@dataclass
class Interpreted:
    id: int
    text: str
    script: Script
    clears: bool  # it calls clear_interpreter(): lines after it wait until it ran


@dataclass(eq=False)
class InterpreterState:
    """One program's interpreter: what is received, interpreted and run, and the ids the state
    commands report (0: none yet)."""

    received: deque[Received] = field(default_factory=deque)  # not yet interpreted
    ready: deque[Interpreted] = field(default_factory=deque)  # interpreted, not yet run
    last_interpreted: int = 0
    last_executed: int = 0
    last_cleared: int = 0
    active: bool = False  # the main thread is in interpreter_mode()
    ending: bool = False  # end_interpreter() was called
    clearing: bool = False  # a clear_interpreter() was interpreted and has not run yet
    size: int = 0  # statements interpreted since the last clear
    functions: set[str] = field(default_factory=set)  # defined by interpreted statements
    stopping: Any = None  # the controlled stop `abort` began: the next statement waits for its end


def state_of(program: Any) -> InterpreterState:
    """The program's interpreter (one per program, as the controller makes one at each start)."""
    state = getattr(program, "interpreter", None)
    if state is None:
        state = program.interpreter = InterpreterState()
    return state  # type: ignore[no-any-return]


# --- the socket's side -----------------------------------------------------------------------


def receive(program: Program | None, line: str, reply: Reply, last: InterpreterState | None = None) -> None:
    """One line from the interpreter socket; `reply` is called with its answer: at once, or when
    the line is interpreted (`interpret`). `last`: the interpreter of the program that ran last,
    for the state commands when none runs."""
    text = line.strip()
    running = program is not None and not program.finished
    if text in CONTROL:
        state = state_of(program) if running else (last or InterpreterState())
        reply(control(program if running else None, state, text))
        return
    if not running:
        reply(f"discard: {INVALID_STATE}: {text}")
        return
    state = state_of(program)
    if len(text) > MAX_LINE:
        reply(f"discard: {TOO_LONG}: {text[:80]}...")
    elif len(state.received) >= MAX_QUEUED:
        reply(f"discard: {TOO_MANY}: {text}")
    else:
        state.received.append(Received(text, reply))


def control(program: Program | None, state: InterpreterState, command: str) -> str:
    """A command answered as soon as it is received."""
    if command == "statelastexecuted":
        value = state.last_executed
    elif command == "statelastinterpreted":
        value = state.last_interpreted
    elif command == "statelastcleared":
        value = state.last_cleared
    elif command == "stateunexecuted":
        value = len(state.ready)
    elif command == "skipbuffer":  # what was interpreted and has not run yet is skipped
        value = len(state.ready)
        state.last_cleared = max(state.last_cleared, *(item.id for item in state.ready), 0)
        state.ready.clear()
        state.clearing = False
    else:  # abort: a movej or movel under way stops (the manual: only those), whoever commanded it
        arm = program.robot.arm if program is not None else None
        motion = arm.motion if arm is not None else None
        value = int(isinstance(motion, JointMove | LinearMove))
        if arm is not None and value:
            arm.stop(float(getattr(motion, "a", 1.4)), linear=isinstance(motion, LinearMove))
            state.stopping = arm.motion
    return f"state: {value}: {command}"


def interpret(program: Program, state: InterpreterState, seconds: float = INTERPRET_SECONDS) -> None:
    """Compile the lines received into the program while it is in interpreter mode (and no
    clear_interpreter() is pending, nor its end), answering each, for about `seconds` of CPU: a flood of lines
    is interpreted over the control steps, which keep their time."""
    until = time.thread_time() + seconds
    while state.active and not (state.clearing or state.ending) and state.received and not program.finished:
        if time.thread_time() > until:
            return
        got = state.received.popleft()
        if state.size >= MAX_INTERPRETED:
            got.reply(f"discard: {TOO_MANY}: {got.text}")
            continue
        compiled = _compile(program, got.text)
        if isinstance(compiled, str):
            got.reply(f"discard: {compiled}: {got.text}")
            continue
        for name, function in compiled.functions.items():
            program.script.functions[name] = function
            state.functions.add(name)
        state.last_interpreted += 1
        state.size += 1
        clears = "clear_interpreter" in _called(compiled.main)
        state.ready.append(Interpreted(state.last_interpreted, got.text, compiled, clears))
        state.clearing = clears
        got.reply(f"ack: {state.last_interpreted}: {got.text}")


def close(program: Any) -> None:
    """The program ended: lines still waiting are discarded, as no program runs to take them."""
    state = getattr(program, "interpreter", None)
    if state is None:
        return
    state.active = False
    state.ready.clear()
    while state.received:
        got = state.received.popleft()
        got.reply(f"discard: {INVALID_STATE}: {got.text}")


# --- compiling ---------------------------------------------------------------------------------


def _compile(program: Program, text: str) -> Script | str:
    """The statements of one line, checked against the running program; else the discard reason."""
    try:
        script = parse(text)
    except ScriptFault:
        return "Syntax error"
    if script.wrapped:  # `def f(): ... end` defines f; nothing runs
        script.main = []
    if not text or (not script.main and not script.functions):
        return "Syntax error"
    if any(stmt.scope == "global" for stmt in script.main):  # the manual: no new globals
        return "Compile error"
    bodies = [script.main, *(f.body for f in script.functions.values())]
    if any("interpreter_mode" in _called(body) for body in bodies):  # no nested interpreter modes
        return "Compile error"
    ours = state_of(program).functions
    if any(name in program.script.functions and name not in ours for name in script.functions):
        return "Compile error"  # the program's own functions stay as they are (the emulator's choice)
    try:
        check_added(program.script.functions, script, *program.names)  # as the program was checked
    except ScriptFault:
        return "Compile error"
    return script


def _called(body: list[Stmt]) -> set[str]:
    """The names `body` calls, in every statement and block."""
    found: set[str] = set()
    stack: list[Expr] = []
    for stmt in body:
        stack.extend(e for e in (stmt.expr, *stmt.index, *(b.cond for b in stmt.branches)) if e is not None)
        for branch in stmt.branches:
            found |= _called(branch.body)
    while stack:
        expr = stack.pop()
        if expr.kind == "call":
            found.add(str(expr.value))
        stack.extend(expr.items)
        stack.extend(e for _, e in expr.kwargs)
    return found


# --- the program's side ----------------------------------------------------------------------


def session(program: Program, stmt: Stmt, frame: dict[str, Any]) -> Any:
    """`interpreter_mode(clearQueueOnEnter=True, clearOnEnd=True)` in the main thread: run what the
    socket sends, in the caller's scope, until end_interpreter()."""
    assert stmt.expr is not None
    if program.current.id != 0:
        raise ScriptFault("interpreter_mode() can only be called in the main thread", stmt.line, 1)
    values, kwargs = yield from program.arguments(stmt.expr, frame)
    flags = [
        truth(script_calls.arg(stmt, values, kwargs, i, name, True), name, stmt.line, 1)
        for i, name in enumerate(("clearQueueOnEnter", "clearOnEnd"))
    ]
    state = state_of(program)
    if state.active:
        raise ScriptFault("interpreter_mode(): nested interpreter modes are not supported", stmt.line, 1)
    state.active, state.ending = True, False
    if flags[0]:
        while state.received:
            got = state.received.popleft()
            got.reply(f"discard: Cleaned up before interpretation: {got.text}")
    try:
        interpret(program, state)
        run = 0
        while not state.ending:
            braking = state.stopping is not None and program.robot.arm.motion is state.stopping
            if braking or not state.ready or run >= MAX_PER_STEP:
                run = 0
                yield  # idle (or enough for one step, or an aborted move stopping) until the next step
                interpret(program, state)
                continue
            item = state.ready.popleft()
            state.last_executed = item.id
            started = program.clock
            yield from _alongside(program.block(item.script.main, frame), program, state)
            run = run + 1 if program.clock == started else 0
    finally:
        state.active = False
        if flags[1] or program.finished:
            _clear(program, state)
        else:
            state.ready.clear()


def _alongside(steps: Any, program: Program, state: InterpreterState) -> Any:
    """Run a statement's steps; at each of its waits (a move's control steps) what the socket
    brought meanwhile is interpreted and answered, as the controller acknowledges lines while it
    runs the earlier ones."""
    while True:
        try:
            next(steps)
        except StopIteration:
            return
        try:
            yield
        except GeneratorExit:
            steps.close()
            raise
        interpret(program, state)


def _clear(program: Program, state: InterpreterState) -> None:
    """Everything the interpreter mode interpreted leaves the program: its functions, and the
    threads they run ("Threads started in current interpreter session will be stopped")."""
    for thread in list(program.threads.values()):
        if thread.id and thread.name in state.functions and thread is not program.current:
            close_thread(thread)
    for name in state.functions:
        program.script.functions.pop(name, None)
    state.functions.clear()
    state.ready.clear()
    state.size = 0
    state.last_cleared = state.last_interpreted


@_enter("end_interpreter")
def end_interpreter(runner: Runner, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> None:
    state_of(runner).ending = True  # from any thread; a statement under way finishes first


@_enter("clear_interpreter")
def clear_interpreter(runner: Runner, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> None:
    state = state_of(runner)
    if not state.active:
        raise ScriptFault("clear_interpreter() can only be called in interpreter mode", stmt.line, 1)
    _clear(runner, state)  # type: ignore[arg-type]
    state.clearing = False
    interpret(runner, state)  # type: ignore[arg-type]


def waiting(runner: Runner, stmt: Stmt, args: list[Any], kwargs: dict[str, Any]) -> Any:
    """interpreter_mode() reached inside an expression: the scope is the program's globals."""
    program: Any = runner
    expr = Expr("call", "interpreter_mode", column=stmt.column, line=stmt.line)
    call = Stmt("call", stmt.line, "", "interpreter_mode", expr, stmt.column)
    yield from session(program, call, program.globals)
