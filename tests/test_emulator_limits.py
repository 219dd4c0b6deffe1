"""Each emulator port keeps its per-client limits (guard.py), with real sockets on loopback."""

from __future__ import annotations

import socket
import time

import pytest

from rtde_spec._generated import rtde_models as gen
from rtde_spec.emulator.ports.guard import ClientLimits, split_lines
from rtde_spec.emulator.ports.script_framer import ScriptFramer
from rtde_spec.emulator.server import EmulatorConfig, EmulatorThread
from rtde_spec.errors import ProtocolError


def closed_within(sock: socket.socket, seconds: float) -> bool:
    """Whether the peer closed the connection within `seconds` (what arrives before is read away)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        sock.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            if not sock.recv(65536):
                return True
        except TimeoutError:
            return False
        except OSError:
            return True
    return False


def emulator(**limits: object) -> EmulatorThread:
    config = EmulatorConfig(
        rtde_port=0,
        primary_port=0,
        secondary_port=0,
        limits=ClientLimits(**limits),
        realtime_port=None,
        dashboard_port=None,
    )  # type: ignore[arg-type]
    return EmulatorThread(config).start()


def test_a_port_takes_at_most_max_clients_and_closes_the_next() -> None:
    emu = emulator(max_clients=2)
    try:
        first, second = (socket.create_connection(("127.0.0.1", emu.ports["primary"])) for _ in range(2))
        time.sleep(0.2)
        third = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        assert closed_within(third, 3)
        assert not closed_within(first, 0.5) and not closed_within(second, 0.1)
        assert emu.emulator.clients["primary"].refused == 1
        first.close()
        time.sleep(0.3)
        fourth = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        assert not closed_within(fourth, 0.5)  # a place came free
        for s in (second, third, fourth):
            s.close()
    finally:
        emu.stop()


def test_a_silent_rtde_client_is_dropped_but_a_primary_reader_that_never_sends_is_not() -> None:
    emu = emulator(handshake_timeout=0.5)
    try:
        silent = socket.create_connection(("127.0.0.1", emu.ports["rtde"]))
        reader = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        talker = socket.create_connection(("127.0.0.1", emu.ports["rtde"]))
        talker.sendall(gen.RequestProtocolVersion(protocol_version=2).to_bytes())
        assert closed_within(silent, 5)
        assert not closed_within(reader, 1.5)  # it gets Robot State and is kept
        assert not closed_within(talker, 0.1)  # it completed a package in time
        for s in (silent, reader, talker):
            s.close()
    finally:
        emu.stop()


def test_a_half_sent_package_or_line_is_dropped_after_the_stall_timeout() -> None:
    emu = emulator(stall_timeout=0.5)
    try:
        half = socket.create_connection(("127.0.0.1", emu.ports["rtde"]))
        half.sendall(gen.RequestProtocolVersion(protocol_version=2).to_bytes()[:2])
        line = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        line.sendall(b"set_standard_digital_out(1, True)")  # no newline: not run, held
        assert closed_within(half, 5) and closed_within(line, 5)
        assert emu.model.values["actual_digital_output_bits"] == 0
    finally:
        emu.stop()


def test_bytes_that_are_no_urscript_or_too_long_a_line_drop_a_primary_client() -> None:
    emu = emulator(max_input_bytes=4096)
    try:
        binary = socket.create_connection(("127.0.0.1", emu.ports["secondary"]))
        binary.sendall(b"\x00\x01\x02garbage\n")
        long = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        long.sendall(b"x" * 5000)
        assert closed_within(binary, 5) and closed_within(long, 5)
        assert emu.emulator.clients["primary"].dropped == 1 and emu.emulator.clients["secondary"].dropped == 1
    finally:
        emu.stop()


def test_a_program_split_over_reads_runs_once_its_end_arrives() -> None:
    emu = emulator()
    try:
        sock = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        sock.sendall(b"def p():\n  set_standard_digital_out(3, True)\n")
        time.sleep(0.3)
        assert emu.call(lambda: emu.model.values["actual_digital_output_bits"]) == 0
        sock.sendall(b"end\n")
        deadline = time.monotonic() + 3
        while emu.call(lambda: emu.model.values["actual_digital_output_bits"]) != 8:
            assert time.monotonic() < deadline
            time.sleep(0.05)
        assert [text for _, text in emu.emulator.primary.scripts][-1].startswith("def p():")
        sock.close()
    finally:
        emu.stop()


@pytest.mark.parametrize(
    "block",
    [
        # a condition over three lines, as Robotiq's vacuum URCap preamble writes its waits
        "  while (get_standard_digital_in(0) and\n         not get_standard_digital_in(1) and\n"
        "         True):\n    sleep(0.01)\n  end\n",
        '  if "#" == "#":\n    textmsg("a # in a string")\n  end\n',  # no comment starts in a string
        "  if True: textmsg(1) end\n",  # a block on one line
        "  t = struct(sec=1, end=2)\n  textmsg(t.sec + t.end)\n",  # time()'s fields: keywords after a dot
    ],
)
def test_a_program_is_cut_at_its_own_end_whatever_its_blocks_look_like(block: str) -> None:
    """The port runs the whole program, not its first lines up to an inner `end` (a syntax error
    then, and the rest run as loose lines)."""
    emu = emulator()
    try:
        sock = socket.create_connection(("127.0.0.1", emu.ports["primary"]))
        sock.sendall(f"def p():\n{block}  set_standard_digital_out(3, True)\nend\n".encode())
        deadline = time.monotonic() + 3
        while emu.call(lambda: emu.model.values["actual_digital_output_bits"]) != 8:
            assert time.monotonic() < deadline
            time.sleep(0.05)
        assert [text.count("\n") for _, text in emu.emulator.primary.scripts] == [block.count("\n") + 3]
        sock.close()
    finally:
        emu.stop()


def test_script_framer_cuts_lines_and_programs() -> None:
    framer = ScriptFramer()
    assert framer.feed(b"textmsg(1)\nset_standard_digital_out(1, Tr") == ["textmsg(1)\n"]
    assert framer.pending == len("set_standard_digital_out(1, Tr")
    assert framer.feed(b"ue)\ndef p():\n  if x:\n    y()\n  else:\n    z()\n  end\n") == [
        "set_standard_digital_out(1, True)\n"
    ]
    assert framer.pending > 0  # the program is open
    assert framer.feed(b"end\nsleep(1)\n") == [
        "def p():\n  if x:\n    y()\n  else:\n    z()\n  end\nend\n",
        "sleep(1)\n",
    ]
    assert framer.pending == 0


@pytest.mark.parametrize("data", [b"\x00", b"abc\x1b[0m\n", b"\xff\xfe\n"])
def test_script_framer_refuses_bytes_that_are_no_text(data: bytes) -> None:
    with pytest.raises(ProtocolError):
        ScriptFramer().feed(data)


class _Searched(bytearray):
    """A held buffer that counts the bytes searched for line ends in it."""

    scanned = 0

    def split(self, *args: object, **kwargs: object) -> list[bytearray]:  # type: ignore[override]
        _Searched.scanned += len(self)
        return super().split(*args, **kwargs)  # type: ignore[arg-type]

    def rfind(self, *args: object, **kwargs: object) -> int:  # type: ignore[override]
        _Searched.scanned += len(self)
        return super().rfind(*args, **kwargs)  # type: ignore[arg-type]


def test_a_long_line_coming_in_small_reads_is_not_searched_again_on_every_read() -> None:
    """A dashboard or interpreter client trickling a line up to the port's 1 MB limit in 100-byte
    reads had the held bytes re-split on every read (6 s of the server's loop): each byte held is
    now searched about once, and the lines still come out whole."""
    _Searched.scanned = 0
    buffer: bytearray = _Searched()
    reads = [b"x" * 100] * 2000 + [b"x\nnext", b" line\n"]
    got: list[bytearray] = []
    for data in reads:
        buffer, lines = split_lines(buffer if isinstance(buffer, _Searched) else _Searched(buffer), data)
        got += lines
    assert got == [b"x" * 200_001, b"next line"] and buffer == b""
    assert _Searched.scanned < 2 * sum(map(len, reads))  # before: ~200 MB for these 200 kB

    _Searched.scanned = 0
    framer = ScriptFramer()
    framer._held = _Searched()
    scripts = [s for data in reads for s in framer.feed(data)]
    assert "".join(scripts) == "x" * 200_001 + "\nnext line\n"
    assert _Searched.scanned < 2 * sum(map(len, reads))
