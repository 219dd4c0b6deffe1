"""A client that writes to a program's socket without pacing (URCL's `tool_contact_example` and
`script_command_example` write as fast as their loop turns) against the interpreter's threads.

The program reads its socket in order, one record per `socket_read_binary_integer`, as the
Script Manual says; a read of a record already there costs no control step, so a reading loop
goes on until its share of the step is over. The threads share the step round robin, so the
reading loop cannot take the step from the thread that moves the arm: that thread still runs in
every step, on the newest command the reader has stored (docs/decisions.md). The reader falls
behind such a client all the same (Python reads slower than a controller): the emulator says so
once in its log when the socket's buffer is full.
"""

from __future__ import annotations

import logging
import socket
import struct
import threading

import pytest

from rtde_spec.emulator.controller.model import ControllerModel
from rtde_spec.emulator.urscript.sockets import MAX_BUFFER

RECORDS = MAX_BUFFER // 4 + 50_000  # more than the socket holds unread, and than the steps read
STEPS = 100


def flood_program(port: int) -> str:
    return f"""def prog():
  global turns = 0
  global last = 0
  thread mover():
    while True:
      turns = turns + 1
      speedj([0, 0, 0, 0, 0, 0.01], 1.0, 0.002)
    end
  end
  socket_open("127.0.0.1", {port}, "flood")
  run mover()
  while True:
    v = socket_read_binary_integer(1, "flood", 0)
    if v[0] > 0:
      if v[1] != last + 1:
        textmsg("out of order: ", v[1], " after ", last)
      end
      last = v[1]
    end
  end
end
"""


def test_a_reader_of_an_unpaced_client_leaves_the_mover_its_turn_in_every_step(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="rtde_spec.emulator")
    with socket.create_server(("127.0.0.1", 0)) as server:
        server.settimeout(10)
        model = ControllerModel("5.15.0")
        program = model.run_script(flood_program(server.getsockname()[1]))
        assert program is not None
        conn, _ = server.accept()
        data = b"".join(struct.pack(">i", i) for i in range(1, RECORDS + 1))
        writer = threading.Thread(target=conn.sendall, args=(data,), daemon=True)
        writer.start()
        try:
            while model.program is not None and not program.globals.get("last"):
                model.tick(model.step + 1)  # the program connects, the first records come
            start = model.step
            turns = int(program.globals["turns"])
            for _ in range(STEPS):
                model.tick(model.step + 1)
            events = [(e.kind, e.text) for e in model.drain_events()]
            assert model.program is program, events  # no fault: it runs on
            assert not [text for kind, text in events if kind == "text"], events  # in order
            read = int(program.globals["last"])
            assert 0 < read < RECORDS  # still reading: the client is ahead of it
            # the mover had its turn in every step the reader read through
            assert int(program.globals["turns"]) - turns >= model.step - start - 1
            behind = [r.getMessage() for r in caplog.records if "writes faster" in r.getMessage()]
            assert len(behind) == 1 and "'flood'" in behind[0], behind  # said once
        finally:
            conn.close()
            writer.join(10)
            if model.program is not None:
                model.stop_program()
