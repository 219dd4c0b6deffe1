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
    if code == 0:  # NONE
        return None, pos
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


def _program_state_messages(
    seconds: float, controller: str = "5.15.0", program: bytes = PROGRAM
) -> list[bytes]:
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
            sock.sendall(program)
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


# twelve globals of 80 kB each (64 kB of each sent, a string's most): 780 kB of values, which one
# update a tick once tried to send whole
BIG = (
    b'def big_globals():\n  s = "0123456789"\n  i = 0\n'
    + b"  while i < 12:\n    s = str_cat(s, s)\n    i = i + 1\n  end\n"
    + b"".join(b"  x%d = str_cat(s, s)\n  sync()\n" % i for i in range(12))
    + b"  n = 0\n  while True:\n    n = n + 1\n    sleep(0.1)\n  end\nend\n"
)


def test_big_globals_come_a_bounded_update_at_a_time_and_the_program_runs_on() -> None:
    """Each update carries the values from its start index on, as many as fit 128 kB (the emulator's
    bound; a value alone over it is NONE), and the next goes on from there. Sending every value
    every 100 ms stalled the hostile-program test: a program holding megabytes in its globals
    made every tick's update megabytes long, and the port fell silent."""
    messages = _program_state_messages(2.5, program=BIG)
    updates = [m for m in messages if m[13] == 1]
    assert len(updates) >= 12
    assert max(len(m) for m in updates) < (128 << 10) + 64
    assert any(isinstance(v, str) and len(v) == 65535 for v in _all_values(updates))
    starts = [struct.unpack_from(">H", m, 14)[0] for m in updates]
    assert len(set(starts)) > 2 and set(starts) <= set(range(15))  # s, i, x0..x11, n
    counters = []
    for update, start in zip(updates, starts, strict=True):
        values, pos = [], 16
        while pos < len(update):
            value, pos = _value(update, pos)
            values.append(value)
            pos += 1
        if start <= 14 < start + len(values):
            counters.append(values[14 - start])
    assert counters == sorted(counters) and counters[-1] > counters[0]  # the program ran on


def _all_values(updates: list[bytes]) -> list[object]:
    found: list[object] = []
    for update in updates:
        pos = 16
        while pos < len(update):
            value, pos = _value(update, pos)
            found.append(value)
            pos += 1
    return found
