"""URScript the emulator understands: the I/O calls a test sends to the primary or secondary
port, which a controller runs and then shows on RTDE and in Robot State.

Only one call per line, with literal arguments (`set_standard_digital_out(3, True)`),
inside or outside a `def ...: ... end` program; the calls run at once, in order (no
motion, no timing). Every other line is kept but does nothing, as the emulator says in
its log.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtde_spec.emulator.model import ControllerModel

_CALL = re.compile(
    r"^\s*(\w+)\(\s*(\d+)\s*,\s*(True|False|true|false|[-+]?[0-9.]+(?:[eE][-+]?\d+)?)\s*\)\s*$"
)
# script function -> (output group, pins it has), names as in the Script manual
_DIGITAL = {
    "set_standard_digital_out": ("standard", 8),
    "set_configurable_digital_out": ("configurable", 8),
    "set_tool_digital_out": ("tool", 2),
}
_ANALOG = {"set_standard_analog_out": 2}  # the deprecated set_digital_out/set_analog_out are not run


def run_script(model: ControllerModel, text: str) -> list[str]:
    """Apply the I/O calls of `text` to the controller model; returns the calls applied."""
    applied = []
    for line in text.splitlines():
        found = _CALL.match(line)
        if found is None:
            continue
        name, pin, arg = found.group(1), int(found.group(2)), found.group(3)
        if name in _DIGITAL:
            group, pins = _DIGITAL[name]
            if pin >= pins or arg.lower() not in ("true", "false"):
                continue
            on = arg.lower() == "true"
            model.apply_inputs(
                {f"{group}_digital_output_mask": 1 << pin, f"{group}_digital_output": int(on) << pin}
            )
        elif name in _ANALOG and pin < _ANALOG[name] and arg.lower() not in ("true", "false"):
            # a fraction of the output's range, as the RTDE input; the domain (V or mA) stays
            model.values[f"standard_analog_output{pin}"] = min(1.0, max(0.0, float(arg)))
        else:
            continue
        applied.append(line.strip())
    return applied
