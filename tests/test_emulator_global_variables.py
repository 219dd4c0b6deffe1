"""Global Variables Setup and Update messages on the primary port, as a real controller sends them.

UR's primary interface document: the setup message lists the program's global variables,
"sent once when program starts. Afterwards update messages are sent every 100ms" with the
values in the setup's order (a type byte, the data, a new line after each). UnderAutomation's
Universal Robots SDK (PyPI underautomation_universalrobots 9.4.0.1) builds
`primary_interface.global_variables.get_all()` from them (its example
examples/primary_interface/primary_interface_global_variables.py lists names, values and
types); the emulator sent an empty setup and no updates, so the SDK found no variables. The SDK
also says values are decoded another way from 3.2 to 5.8, a way no public document gives: those
versions get the names and no values.
The bytes are read here by hand, as that client reads them, over real sockets on loopback.
"""

from __future__ import annotations

import socket
import struct

from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread

from .test_emulator_fidelity import raw_messages

PROGRAM = b"""def globals_demo():
  counter = 0
  name = "abc"
  pos = p[0.1, 0.2, 0.3, 0, 0, 0]
  if True:
    flag = True
  end
  q = [1, 2, 3]
  while True:
    counter = counter + 1
    sleep(0.1)
  end
end
"""


def _value(data: bytes, pos: int) -> tuple[object, int]:
    """One typed value (GlobalVariableType codes of the document's Value Types) and where it ends."""
    code = data[pos]
    pos += 1
    if code == 15:  # INT
        return struct.unpack_from(">i", data, pos)[0], pos + 4
    if code in (3, 4):  # CONST_STRING, VAR_STRING
        (size,) = struct.unpack_from(">H", data, pos)
        return data[pos + 2 : pos + 2 + size].decode(), pos + 2 + size
    if code == 12:  # POSE: 6 floats
        return tuple(round(v, 5) for v in struct.unpack_from(">6f", data, pos)), pos + 24
    if code == 13:  # BOOL
        return bool(data[pos]), pos + 1
    if code == 17:  # LIST: count, then (type, value) each
        (count,) = struct.unpack_from(">H", data, pos)
        pos += 2
        items = []
        for _ in range(count):
            item, pos = _value(data, pos)
            items.append(item)
        return items, pos
    raise AssertionError(f"type byte {code} at {pos - 1}")


def _program_state_messages(seconds: float, controller: str = "5.15.0") -> list[bytes]:
    """The Program State messages (type 25) a primary client gets while PROGRAM runs."""
    config = EmulatorConfig(
        controller=controller,
        rtde_port=None,
        primary_port=0,
        secondary_port=None,
        realtime_port=None,
        dashboard_port=None,
    )
    with EmulatorThread(config) as emu:
        with socket.create_connection(("127.0.0.1", emu.ports["primary"]), timeout=5) as sock:
            sock.sendall(PROGRAM)
            return [message for message in raw_messages(sock, seconds) if message[4] == 25]


def test_setup_names_the_program_globals_and_updates_bring_their_values_every_100_ms() -> None:
    messages = _program_state_messages(1.5)
    setups = [m for m in messages if m[13] == 0]
    updates = [m for m in messages if m[13] == 1]
    assert len(setups) == 1
    assert struct.unpack_from(">H", setups[0], 14)[0] == 0  # start index
    assert setups[0][16:] == b"counter\nname\npos\nflag\nq\n"
    assert 8 <= len(updates) <= 16  # every 100 ms for 1.5 s, less the program's start
    counters = []
    for update in updates:
        assert struct.unpack_from(">H", update, 14)[0] == 0
        values, pos = [], 16
        while pos < len(update):
            value, pos = _value(update, pos)
            assert update[pos] == 0x0A, f"no separator after value {len(values)}"
            values.append(value)
            pos += 1
        assert values[1:] == ["abc", (0.1, 0.2, 0.3, 0.0, 0.0, 0.0), True, [1, 2, 3]]
        counters.append(values[0])
    assert counters == sorted(counters) and counters[-1] > counters[0]


def test_before_5_9_the_setup_names_the_globals_and_no_values_are_sent() -> None:
    messages = _program_state_messages(1.0, controller="3.15.8")
    assert [m[16:] for m in messages if m[13] == 0] == [b"counter\nname\npos\nflag\nq\n"]
    assert [m for m in messages if m[13] == 1] == []
