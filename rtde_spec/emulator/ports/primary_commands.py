"""The plain commands a controller takes on its script ports (30001/30002/30003) besides URScript.

Drivers send these as lines of their own, outside any program: UR's C++ client library
(URCL, src/primary/primary_client.cpp) sends `power on`, `power off`, `set robotmode run`
(brake release, powering the arm first if need be), `set unlock protective stop` and
`stop program`; its driver starts with `stop program`. The older ROS driver
(ros-industrial/universal_robot, ur_driver/src/ur_driver/driver.py, RobotCommands) also sends
`pause program` and `resume program` (the latter after the arm is back in run mode), and so
does UnderAutomation's Universal Robots SDK 9.4 (primary_interface.commands.pause_program and
resume_program, one line each on port 30001). `set sim` and `set real` switch between the
simulated arm and the real one (python-urx, urx/urrobot.py URRobot.set_simulation, sends them as
a program on the secondary port; UnderAutomation's SDK: commands.set_simulated and set_real);
Robot Mode Data's isRealRobotEnabled is false while simulating. The controller acts on them at
once and does not parse them as URScript, so they are taken out of what a client sends
before the interpreter sees it. They act on the same model as the dashboard's commands
(modes.py); they have no reply, a client watches the Robot State (robot mode, protective
stop, program running) instead.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel

log = logging.getLogger("rtde_spec.emulator")
_BLOCK = re.compile(r"^(def|sec|thread|if|while)\b.*:$")  # what opens a block, as the framer cuts it


def _brake_release(model: ControllerModel) -> bool:
    return model.release_brakes()


def _run(model: ControllerModel) -> bool:
    """`set robotmode run`: from power off too, the arm is powered and its brakes released (URCL's
    tests against URSim, tests/test_primary_client.cpp, power off and then expect RUNNING)."""
    return model.power_on() and model.release_brakes()


def _resume(model: ControllerModel) -> bool:
    """`resume program`: a paused program goes on, as the dashboard's play resumes it; nothing starts."""
    return model.program is not None and model.paused and model.play()


def _noop(model: ControllerModel) -> bool:
    return True  # popups are not shown by the emulator: there is nothing to close


# command line (spaces collapsed) -> what it does to the model
COMMANDS: dict[str, Callable[[ControllerModel], bool]] = {
    "power on": lambda m: m.power_on(),
    "power off": lambda m: m.power_off(),
    "brake release": _brake_release,
    "set robotmode run": _run,
    "stop program": lambda m: m.stop_program(),
    "pause program": lambda m: m.pause_program(),
    "resume program": _resume,
    "unlock protective stop": lambda m: m.unlock_protective_stop(),
    "set unlock protective stop": lambda m: m.unlock_protective_stop(),
    "set sim": lambda m: m.simulate(True),
    "set real": lambda m: m.simulate(False),
    "close popup": _noop,
    "close safety popup": _noop,
}


def command_of(line: str) -> Callable[[ControllerModel], bool] | None:
    """The plain command a line is (comments and spacing aside), None when it is URScript."""
    code = " ".join(line.split("#", 1)[0].split())
    return COMMANDS.get(code)


def take_commands(model: ControllerModel, text: str) -> str:
    """Run the plain command lines of `text` on the model; the rest is returned for the interpreter.

    A program (`def`/`sec`, or any block the framer kept whole) is URScript through and
    through and is returned untouched.
    """
    first = next((line.split("#", 1)[0].strip() for line in text.splitlines() if line.strip()), "")
    if _BLOCK.match(first):
        return text
    rest: list[str] = []
    for line in text.splitlines():
        action = command_of(line)
        if action is None:
            rest.append(line)
            continue
        accepted = action(model)
        log.info("primary command %r %s", line.strip(), "done" if accepted else "had no effect in this state")
    return "\n".join(rest) + "\n" if any(r.strip() for r in rest) else ""
