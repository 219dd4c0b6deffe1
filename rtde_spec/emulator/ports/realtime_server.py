"""The emulator's real-time ports (30003, read-only 30013): one message per control step.

The message is the controller version's layout from the spec (rtde_spec.realtime), its
fields filled from the RTDE outputs the spec names as carrying the same quantity, so
the three interfaces show one robot. Built once per step and only while a client is
connected. What a client sends on 30003 is URScript, cut and run as on the primary
ports (script_framer.py); the read-only port drops it. Clients keep guard.py's limits, but one
that stopped reading keeps its connection and misses messages: ur_rtde's script client never
reads 30003 and sends its path moves and re-uploads through it for as long as it runs.
"""

from __future__ import annotations

import logging
import struct
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.realtime import REALTIME
from rtde_spec.emulator.ports.guard import Port
from rtde_spec.emulator.ports.script_framer import ScriptPort
from rtde_spec.realtime import layout_for

if TYPE_CHECKING:
    from rtde_spec.emulator.controller.model import ControllerModel
    from rtde_spec.emulator.ports.primary_server import PrimaryHub

log = logging.getLogger("rtde_spec.emulator")


class RealtimeHub:
    """Connections of the real-time ports and the message each control step sends them."""

    def __init__(self, model: ControllerModel, primary: PrimaryHub) -> None:
        self.model, self.primary = model, primary
        self.layout = layout_for(model.version)
        sources = {f["name"]: f.get("rtde") for f in REALTIME["fields"]}
        self.sources = [(name, sources.get(name)) for name in self.layout.names]
        # the hot path: (RTDE output, value count) per field, in message order; time is the model's
        self._plan = [
            (None if name == "time" else source, count)
            for (name, source), count in zip(self.sources, self.layout.counts, strict=True)
        ]
        self.connections: set[RealtimeConnection] = set()
        self.sent = 0

    def values(self) -> dict[str, Any]:
        """The message's fields by name, from the model's outputs (what is missing stays zero)."""
        values = self.model.values
        out = {name: values.get(source) for name, source in self.sources if source is not None}
        out["time"] = self.model.time  # the timestamp output is not on every version (CB3 < 3.3)
        return out

    def message(self) -> bytes:
        """This step's message: the model's values packed straight into the layout's struct."""
        values = self.model.values
        flat: list[Any] = [self.layout.size, self.model.time]
        for source, count in self._plan[1:]:
            value = values.get(source) if source is not None else None
            if value is None:
                flat.extend((0.0,) * count)
            elif count == 1:
                flat.append(value)
            else:
                flat.extend(value)
        try:
            return self.layout.plan.pack(*flat)
        except struct.error:  # a value of the wrong shape: the checked path names it
            return self.layout.encode(self.values())

    def send(self) -> None:
        """Every control step: the message to each client (built only when one is connected)."""
        if not self.connections:
            return
        data = self.message()
        for conn in list(self.connections):
            conn.write(data)
        self.sent += 1


class RealtimeConnection(ScriptPort):
    """One client of a real-time port: the stream of messages; on 30003 its scripts run."""

    skips_when_behind = True  # a script sender that never reads keeps its connection, as on a robot

    def __init__(self, hub: RealtimeHub, port: Port, number: int, read_only: bool) -> None:
        super().__init__(port)
        self.hub, self.number, self.read_only = hub, number, read_only

    def opened(self) -> None:
        self.hub.connections.add(self)

    def closed(self) -> None:
        self.hub.connections.discard(self)

    def run_script(self, text: str) -> None:
        self.hub.primary.run(self.number, text)
