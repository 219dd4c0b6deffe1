"""The ports: RTDE, primary/secondary, real-time and dashboard servers, the interpreter socket,
and the state messages they send."""

from rtde_spec._generated.urscript_ports import INTERPRETER_PORT  # the CLI names it without the emulator

__all__ = ["INTERPRETER_PORT"]
