"""URScript's interpreter: the main program and its threads, scheduled on the control step.

Each thread is a generator. Every control step (2 ms on e-Series, 8 ms on CB3) each live
thread, in the order they were started, runs statements until it waits — a motion command
for its step of motion, `sync()` or `sleep()` — then yields, as the controller's threads do.
The interpreter has the time left before the step is due, and SLICE of the step in CPU time
whatever the deadline, so a loaded machine does not change what a program does; the threads
share it round robin (budgets.py): a thread still running when its share is over is
preempted and goes on when time is left, else at the next step's start (before the arm moves:
`catch_up`), so the control loop keeps its time and no thread starves the others. A thread that runs
STEP_BUDGET statements without waiting (a function run inside an expression cannot be
preempted: this bounds it), or one statement that takes STATEMENT_SECONDS of CPU (a call of
64,000 arguments; evaluator.py), gets the controller's "Runtime is too much behind" runtime
error; a program whose process grows MEMORY_BUDGET past what it held when the program started
gets "out of memory". So the servers never wait on a program, nor run out of memory. `kill`
ends a thread, `join` waits for it; when the main program ends, stops or faults its threads
end with it. Names resolve in the function's locals, then the program's globals; assigning a
name the globals hold changes the global unless `local` says otherwise, as the Script manual
describes. Expressions that may call a user function (which may wait) are evaluated step by
step (`evaluator.py`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Generator, Iterator
from contextlib import contextmanager
from typing import Any

from rtde_spec.emulator.arm.motion import MotionError
from rtde_spec.emulator.urscript import builtins, interpreter_mode, sockets
from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript import values as urscript_ops
from rtde_spec.emulator.urscript.budgets import SLICE, Budget, resident_bytes
from rtde_spec.emulator.urscript.checker import check
from rtde_spec.emulator.urscript.evaluator import Evaluator, Frame, Return, Steps, runtime_text
from rtde_spec.emulator.urscript.events import ScriptEvent
from rtde_spec.emulator.urscript.interfaces import Robot, Wait
from rtde_spec.emulator.urscript.lookahead import next_waiting
from rtde_spec.emulator.urscript.nodes import Script, ScriptFault, Stmt
from rtde_spec.emulator.urscript.script_threads import Flow, Killed, LoopTurn, ScriptThread, close_thread
from rtde_spec.emulator.urscript.watchdogs import check_watchdogs
from rtde_spec.errors import RtdeSpecError

PROGRAM_ERRORS = (ArithmeticError, ValueError, TypeError, IndexError, KeyError, RecursionError, MemoryError)
"""What a statement's Python may raise on a program's values: the program's runtime exception."""

STEP_BUDGET = 10_000  # statements (and loop turns) one thread may run without waiting
MEMORY_BUDGET = 256 << 20  # bytes the process may grow while a program runs
MEMORY_EVERY = 10  # control steps between looks at the process's memory
MAX_THREADS = 64  # threads running at once

__all__ = ["PROGRAM_ERRORS", "SLICE", "STEP_BUDGET", "Program", "runtime_text"]


class Program(Evaluator):
    """One running program; `advance(dt)` once per control step (dt in s of real time)."""

    def __init__(self, script: Script, robot: Robot) -> None:
        super().__init__(script, robot)
        self.name = script.name or "script"
        self.applied: list[str] = []  # the I/O calls run, as written
        self.clock = 0.0
        self.finished = False
        self.fault: ScriptFault | None = None
        self.cpu = 0.0  # interpreter CPU seconds (its thread's), all steps: benchmarks report it per step
        self.steps_run = 0
        self.preemptions = 0  # threads sent on to the next step, still preempted at a step's end
        self._epoch = 0
        self._slice_end = 0.0  # perf_counter: the running thread's share may be over (the CPU time says)
        self._cpu_slice_end = 0.0  # thread_time: the running thread's share is over
        hz = float(getattr(robot, "base_hz", 0) or 500)
        self.step_seconds = 1.0 / hz
        self._memory_start = resident_bytes()
        line, version = getattr(robot, "line", None), getattr(robot, "version", None)
        known = builtins.names_for(line.id, str(version), line.inherits) if line else builtins.names()
        self.names = (known, frozenset(script_calls.WAITS | set(builtins.WAITING)))  # interpreter mode's too
        check(script, *self.names)  # as this version compiles
        main = ScriptThread(0, self.name, self._main())
        self.threads: dict[int, ScriptThread] = {0: main}
        self.current = main
        self._next_id = 1

    # --- scheduling --------------------------------------------------------------------------

    def catch_up(self) -> Budget | None:
        """Run the threads preempted at the end of the last step on to their next wait, before
        the arm takes this step; the step's budget it spent from, for `advance` to go on with.

        The controller's interpreter finishes what a driver's thread computes between two
        motions (a spline segment's coefficients) inside the step; this one is slower, and a
        loaded machine can stall it there. The motion that thread then commands starts in
        this step, as on the controller, instead of the arm holding the last one a step longer
        (a URCL-style spline once ended one step at its via point's speed past its end). It is still
        the last step's work: the clock does not move, and it spends this step's budget. Each
        late thread gets the share it would have in the step's round, so a thread that never
        waits does not take the step from the others (`advance` runs it again only if time is left).
        """
        live = [t for t in self.threads.values() if not t.done]
        late = [t for t in live if t.preempted]
        if not late or self.finished:
            return None
        budget = Budget(self.step_seconds)
        with self._running():
            for thread in late:
                thread.caught = True
            self._round(late, budget, len(live))
        return budget

    def advance(self, dt: float = 0.0, budget: Budget | None = None) -> None:
        """One control step: the clock moves by `dt`, each thread runs until it waits (or its
        share of `budget`, this step's, is over: a new one when None)."""
        if self.finished:
            return
        self.clock += dt
        self._epoch += 1
        self.steps_run += 1
        budget = budget or Budget(self.step_seconds)
        with self._running():
            check_watchdogs(getattr(self, "settings", {}).get("watchdogs"), self.robot, self.name)
            if self.steps_run % MEMORY_EVERY == 0:
                self._memory()
            threads = [t for t in self.threads.values() if not t.done]
            for thread in threads:
                if not thread.preempted:  # a thread preempted last step has not waited since
                    thread.ran = 0
            # a thread still preempted after its share in catch_up goes on only if time is left
            first = [t for t in threads if not (t.caught and t.preempted)]
            for thread in threads:
                thread.caught = False
            self._round(first, budget)
            again = [t for t in threads if (t.preempted or t.rested) and not t.done]
            if again and not self.finished and budget.left():  # round robin while time is left
                self._round(again, budget)
            cut = sum(t.preempted and not t.done for t in threads)
            if cut:
                self.preemptions += cut
                budget.preempted()  # the program wanted more of this step than it had

    @contextmanager
    def _running(self) -> Iterator[None]:
        """Around running threads: a fault ends the program; threads that ended leave the table
        (all of them when the program ended); the interpreter's CPU time is counted."""
        cpu = time.thread_time()
        try:
            yield
        except ScriptFault as fault:
            self.fail(fault)
        except PROGRAM_ERRORS as exc:  # out of no statement (resuming a chain nested past the limit)
            self.fail(ScriptFault(runtime_text(exc), 0, 0))
        finally:
            if self.finished:
                self._end_threads()
            for key in [k for k, t in self.threads.items() if t.done]:
                del self.threads[key]
            self.cpu += time.thread_time() - cpu

    def _round(self, threads: list[ScriptThread], budget: Budget, sharing: int = 0) -> None:
        """Each thread in turn, until it waits or its share of what is left is over (shared by
        `sharing` threads, these first; 0: by these)."""
        for i, thread in enumerate(threads):
            if thread.done or self.finished:
                continue
            self.current = thread
            self._slice_end, self._cpu_slice_end = budget.share(max(sharing, len(threads)) - i)
            thread.preempted = thread.rested = False
            try:
                next(thread.steps)
            except StopIteration:
                thread.done = True
                if thread.id == 0:
                    self.finished = True
                    return

    def _memory(self) -> None:
        """The controller's out-of-memory fault for a program that holds more than MEMORY_BUDGET."""
        grown = resident_bytes() - self._memory_start
        if grown > MEMORY_BUDGET:
            raise ScriptFault(
                f"out of memory: the program holds over {MEMORY_BUDGET >> 20} MB ({grown >> 20} MB)", 0, 0
            )

    def slice_used(self) -> bool:
        """Whether the running thread has used its share of this control step (half the statement
        budget, or its share of the step's time). A call that could wait (a socket read) then rests
        until the other threads had their turn (it goes on in this step if time is left, else in
        the next), as the controller puts a thread that used its time slice to rest (Script
        Manual, thread scheduling): a driver's loop reading a flood of records keeps up step by
        step instead of faulting, and the threads that move the arm keep their turns."""
        if self.current.ran > STEP_BUDGET // 2:
            return True
        self.current.rested = (
            time.perf_counter() > self._slice_end and time.thread_time() > self._cpu_slice_end
        )
        return self.current.rested

    def fail(self, fault: ScriptFault) -> None:
        # kept without its traceback: the frames it holds hold the program (a cycle that would keep
        # every value the program made until a full garbage collection)
        fault.__traceback__ = fault.__context__ = fault.__cause__ = None
        self.finished, self.fault = True, fault
        self._end_threads()
        self.robot.emit(
            ScriptEvent("runtime_exception", fault.text, fault.line, fault.column, program=self.name)
        )

    def stop(self) -> None:
        """End the program and its threads (stop program, a new program, the end of main)."""
        self.finished = True
        self._end_threads()
        self.globals.clear()  # what the program made goes now, not at the next full collection

    def _end_threads(self) -> None:
        sockets.close_all(self)
        interpreter_mode.close(self)
        for thread in list(self.threads.values()):
            if thread is not self.current:
                close_thread(thread)
        self.threads.clear()

    def start_thread(self, name: str, line: int, column: int) -> int:
        """`run name()`: a new thread, first stepped in the next control step; its handle."""
        if len(self.threads) >= MAX_THREADS:
            raise ScriptFault(f"run {name}: more than {MAX_THREADS} threads", line, column)
        function = self.script.functions[name]
        handle = self._next_id
        self._next_id += 1
        self.threads[handle] = ScriptThread(handle, name, self._thread_body(function.body))
        return handle

    def _kill(self, handle: Any) -> None:
        thread = self.threads.get(handle) if isinstance(handle, int) and handle else None
        if thread is None:
            return  # a thread that ended, or a handle of 0: nothing to do, as on the controller
        if thread is self.current:
            raise Killed
        close_thread(thread)

    def _main(self) -> Wait:
        if self.script.wrapped:  # the program def's own variables are the program's globals
            yield from self._block(self.script.functions[self.script.name].body, self.globals)
        else:  # top-level statements: their variables are the globals too
            yield from self._block(self.script.main, self.globals)

    def _thread_body(self, body: list[Stmt]) -> Wait:
        try:
            yield from self._block(body, {})
        except Killed:
            return

    # --- statements --------------------------------------------------------------------------

    def block(self, body: list[Stmt], frame: Frame) -> Steps:
        return self._block(body, frame)

    def _block(self, body: list[Stmt], frame: Frame) -> Steps:
        for i, stmt in enumerate(body):
            if self._count(stmt):
                yield  # the slice is over: this thread goes on in the next step
            try:
                expr = stmt.expr
                if stmt.kind == "assign" and expr is not None and not expr.user:  # the common case, at once
                    self.assign(stmt, frame, self.value(expr, frame))
                    continue
                if stmt.kind == "call" and expr is not None and expr.kind == "call" and not expr.user:
                    self.call_now(stmt, frame)  # a call that cannot wait, at once
                    continue
                signal = yield from self._statement(stmt, frame, next_waiting(body, i + 1))
            except (ScriptFault, Killed, GeneratorExit):
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

    def _count(self, stmt: Stmt) -> bool:
        """One more statement without a wait; True when the thread is to yield (its slice is over).

        Past STEP_BUDGET statements without a wait the loop that never waits faults; past the
        step's CPU budget, where the thread cannot be preempted, the statement faults."""
        thread = self.current
        thread.ran += 1
        if thread.ran > STEP_BUDGET:
            loop = next((loop.stmt for loop in thread.loops if loop.epoch == self._epoch), stmt)
            raise ScriptFault(
                f"Runtime is too much behind: the loop on line {loop.line} did not yield "
                f"({thread.ran} statements without a wait); add sync() or sleep() to it",
                loop.line,
                1,
            )
        if time.perf_counter() < self._slice_end or time.thread_time() < self._cpu_slice_end:
            return False  # (the clock alone is cheap; the CPU time counts when the machine is loaded)
        if self._sync:
            return False  # inside an expression: STEP_BUDGET statements bound it
        thread.preempted = True
        return True

    def _statement(self, stmt: Stmt, frame: Frame, following: Stmt | None) -> Steps:
        kind = stmt.kind
        if kind == "assign":
            assert stmt.expr is not None
            value = (
                self.value(stmt.expr, frame)
                if not stmt.expr.user
                else (yield from self.steps(stmt.expr, frame))
            )
            self.assign(stmt, frame, value)
            return None
        if kind == "if":
            for branch in stmt.branches:
                cond = branch.cond
                if cond is None:
                    return (yield from self._block(branch.body, frame))
                if not cond.user:
                    value = self.value(cond, frame)
                    taken = urscript_ops.condition(value, branch.line, branch.column)
                else:
                    taken = yield from self.condition(branch, frame)
                if taken:
                    return (yield from self._block(branch.body, frame))
            return None
        if kind == "while":
            return (yield from self._while(stmt, frame))
        if kind in ("break", "continue"):
            return Flow(kind)
        if kind == "return":
            if stmt.expr is None:
                return Return(None)
            value = (
                self.value(stmt.expr, frame)
                if not stmt.expr.user
                else (yield from self.steps(stmt.expr, frame))
            )
            return Return(value)
        if kind in ("kill", "join"):
            assert stmt.expr is not None
            handle = self.value(stmt.expr, frame)
            if kind == "kill":
                self._kill(handle)
            else:
                yield from self.wait_for(
                    lambda: not isinstance(handle, int) or not handle or handle not in self.threads
                )
            return None
        if kind == "halt":
            self.finished = True
            yield
            return None
        if kind in ("enter_critical", "exit_critical"):
            return None  # threads only switch where they wait, so a critical section holds already
        assert stmt.expr is not None
        if (
            stmt.name == "interpreter_mode"
            and stmt.expr.kind == "call"
            and stmt.name not in self.script.functions
        ):
            yield from interpreter_mode.session(self, stmt, frame)  # statements run in this scope
            return None
        yield from self.call_statement(stmt, frame, following)
        return None

    def _while(self, stmt: Stmt, frame: Frame) -> Steps:
        branch = stmt.branches[0]
        loop = LoopTurn(stmt, self._epoch)
        loops = self.current.loops
        loops.append(loop)
        try:
            while True:
                loop.epoch = self._epoch
                if self._count(stmt):  # a turn counts, so even an empty body cannot spin forever
                    yield
                if not (yield from self.condition(branch, frame)):
                    return None
                signal = yield from self._block(branch.body, frame)
                if signal is Flow.BREAK:
                    return None
                if isinstance(signal, Return):
                    return signal
        finally:
            if loop in loops:
                loops.remove(loop)

    def wait_for(self, done: Callable[[], bool]) -> Wait:
        while not done():
            yield


Runner = Generator[None, None, None]
