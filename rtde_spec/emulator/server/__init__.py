"""The emulator's server wing: the ports and the control loop (`loop.py`), and how code that is
not asyncio runs one (`embedded.py`: in a background thread, or in a process of its own)."""

from rtde_spec.emulator.server.embedded import EmulatorProcess, EmulatorThread
from rtde_spec.emulator.server.loop import Emulator, EmulatorConfig

__all__ = ["Emulator", "EmulatorConfig", "EmulatorProcess", "EmulatorThread"]
