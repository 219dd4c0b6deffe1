"""URScript sent to the emulator's primary/secondary ports: run as the controller runs it.

`run_script` starts a text as the robot's program (the URScript interpreter is
`urscript/`): I/O calls before the first motion or sleep
take effect at once, motions then run with the control steps. A script that cannot
run becomes a runtime exception event on the model (`model.drain_events()`), never
a silent drop. `ScriptReceiver` joins what a connection sends into whole programs,
since TCP may split a `def ... end` anywhere.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel


def run_script(model: ControllerModel, text: str) -> list[str]:
    """Start `text` on the model; returns the I/O calls that ran at once, as written."""
    program = model.run_script(text)
    return list(program.applied) if program is not None else []
