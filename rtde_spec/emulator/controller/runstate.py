"""How digital outputs follow the program: the runstate choices of the Script manual's
set_runstate_standard/configurable/tool_digital_output_to_value, which PolyScope's preamble sets
from the installation and the controller keeps beyond the program.

0 preserve; 1 low when no program runs; 2 high when none runs; 3 high while one runs, low when it
stops; 4 low when a program ends unscheduled (a runtime exception, as the manual counts a fault or
a protective stop); 5 high from a program's start, low when it ends unscheduled; 6 high with drive
power; 7 low with drive power (the emulator applies these two at the call and at a program's start
and end, not at every power change).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

EVENTS = ("start", "running", "stop", "fault")


def level(state: int, event: str, powered: bool) -> bool | None:
    """The level choice `state` gives an output at `event` (one of EVENTS); None: left as it is."""
    if state == 6:
        return powered
    if state == 7:
        return not powered
    running = event in ("start", "running")
    if state == 1:
        return None if running else False
    if state == 2:
        return None if running else True
    if state == 3:
        return running
    if state == 4:
        return False if event == "fault" else None
    if state == 5:
        return True if event == "start" else (False if event == "fault" else None)
    return None


def levels(
    choices: Mapping[tuple[str, int], int], event: str, powered: bool, only: tuple[str, int] | None = None
) -> Iterator[tuple[tuple[str, int], bool]]:
    """(output, level) for each output whose choice sets it at `event` (all, or `only` that one)."""
    for output, state in choices.items():
        if only is not None and output != only:
            continue
        value = level(state, event, powered)
        if value is not None:
            yield output, value
