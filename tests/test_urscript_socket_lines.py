"""socket_read_line, the deprecated line reader older programs still call (the e-Series Script
Directory documents it beside socket_read_string): a line without its "\\n" or "\\r\\n", "" on a
time-out. Over a real socket on loopback."""

from __future__ import annotations

import socket

from rtde_spec.emulator.controller.model import ControllerModel


def test_lines_come_without_their_newline_and_a_time_out_gives_an_empty_text() -> None:
    with socket.create_server(("127.0.0.1", 0)) as server:
        port = server.getsockname()[1]
        model = ControllerModel("3.15.8")
        model.run_script(
            f"""def prog():
  socket_open("127.0.0.1", {port}, "link")
  textmsg("<", socket_read_line("link"))
  textmsg("<", socket_read_line(socket_name="link", timeout=1))
  textmsg("<", socket_read_line("link", 0.05))
  textmsg("<", socket_read_line("link"))
end"""
        )
        server.settimeout(5)
        for _ in range(3):
            model.tick(model.step + 1)
        peer, _ = server.accept()
        with peer:
            peer.sendall(b"first\r\nsecond\npart")
            for _ in range(100):
                model.tick(model.step + 1)
            peer.sendall(b"ial\n")
            for _ in range(100):
                model.tick(model.step + 1)
    events = model.drain_events()
    assert [e.text for e in events if e.kind == "text"] == ["<first", "<second", "<", "<partial"]
    assert [e for e in events if e.kind == "runtime_exception"] == []
