"""URScript sent to the emulator's primary/secondary ports: run as the controller runs it.

`run_script` starts a text as the robot's program (the URScript interpreter is
`urscript.py`, its runner `program.py`): I/O calls before the first motion or sleep
take effect at once, motions then run with the control steps. A script that cannot
run becomes a runtime exception event on the model (`model.drain_events()`), never
a silent drop. `ScriptReceiver` joins what a connection sends into whole programs,
since TCP may split a `def ... end` anywhere.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtde_spec.emulator.model import ControllerModel

MAX_PENDING = 1 << 20  # bytes of an unfinished program kept per connection


def run_script(model: ControllerModel, text: str) -> list[str]:
    """Start `text` on the model; returns the I/O calls that ran at once, as written."""
    program = model.run_script(text)
    return list(program.applied) if program is not None else []


class ScriptReceiver:
    """Bytes of one connection -> whole scripts: complete lines, and a `def`/`sec` only with its `end`."""

    def __init__(self) -> None:
        self.pending = ""

    def feed(self, data: bytes) -> list[str]:
        self.pending += data.decode("utf-8", "replace")
        if len(self.pending) > MAX_PENDING:  # never ends: keep memory bounded, let the parser report it
            text, self.pending = self.pending, ""
            return [text]
        cut = self.pending.rfind("\n")
        if cut < 0:
            return []
        ready, rest = self.pending[: cut + 1], self.pending[cut + 1 :]
        depth = 0
        last_whole = 0
        offset = 0
        for line in ready.splitlines(keepends=True):
            offset += len(line)
            word = line.strip().split("(")[0].split()
            if word and word[0] in ("def", "sec"):
                depth += 1
            elif line.strip() == "end" and depth > 0:
                depth -= 1
            if depth == 0:
                last_whole = offset
        self.pending = ready[last_whole:] + rest
        whole = ready[:last_whole]
        return [whole] if whole.strip() else []
