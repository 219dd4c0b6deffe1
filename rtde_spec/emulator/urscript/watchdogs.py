"""The RTDE input watchdogs a program set (`rtde_set_watchdog`), looked at every control step."""

from __future__ import annotations

from typing import Any

from rtde_spec.emulator.urscript.events import ScriptEvent
from rtde_spec.emulator.urscript.interfaces import Robot
from rtde_spec.emulator.urscript.nodes import ScriptFault


def check_watchdogs(watchdogs: dict[str, Any] | None, robot: Robot, program: str) -> None:
    """rtde_set_watchdog: an RTDE input not written within 1/min_frequency s pauses the program
    (a text message says which) or stops it (a ScriptFault raised here)."""
    if not watchdogs:
        return
    now = float(getattr(robot, "time", 0.0))
    seen = getattr(robot, "inputs_seen", {})
    for name, (hz, action, since) in watchdogs.items():
        if action == "ignore" or now - max(seen.get(name, since), since) <= 1.0 / hz:
            continue
        text = f"RTDE input watchdog: {name} not written at {hz:g} Hz"
        if action == "stop":
            raise ScriptFault(text, 0, 0)
        pause = getattr(robot, "pause_program", None)
        if pause is not None:
            robot.emit(ScriptEvent("text", text, 0, program=program))
            watchdogs[name] = (hz, action, now)  # once per silence
            pause()
