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


def test_a_socket_still_opening_closes_when_the_program_is_stopped() -> None:
    """URCL's instruction executor test (tests/test_instruction_executor.cpp:197-200) stops the driver's
    program with `stop program` just after it started and waits 1 s for its reverse interface to drop.
    The stop came while the program's socket_open("reverse_socket") waited for its connection: the
    socket was in no table, stayed open, and URCL's connection never ended (the next tests hung).
    Here the server's accept queue is full, so the program's connect waits; once the program is
    stopped, no connection of it may arrive later, or it must be closed at once."""
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(0)
    port = listener.getsockname()[1]
    filler = socket.create_connection(("127.0.0.1", port))  # the one place in the accept queue
    model = ControllerModel("5.15.0")
    try:
        model.run_script(f'def prog():\n  socket_open("127.0.0.1", {port}, "s")\n  textmsg("open")\nend')
        for _ in range(5):
            model.tick(model.step + 1)
        assert model.program is not None  # still in socket_open
        assert model.stop_program()
        listener.accept()[0].close()  # room for the program's connection, if it still tries
        listener.settimeout(3.0)
        try:
            late, _ = listener.accept()
        except TimeoutError:
            return  # the program's connection went with it
        late.settimeout(1.0)
        try:
            assert late.recv(1) == b""
        except TimeoutError:
            raise AssertionError("the stopped program's connection stayed open") from None
        finally:
            late.close()
    finally:
        filler.close()
        listener.close()
