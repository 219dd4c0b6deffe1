"""The running program, as the controller model knows it (the interpreter is urscript/)."""

from rtde_spec.emulator.urscript.interpreter import PROGRAM_ERRORS, STEP_BUDGET, Program, runtime_text

__all__ = ["PROGRAM_ERRORS", "STEP_BUDGET", "Program", "runtime_text"]
