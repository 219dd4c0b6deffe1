"""URScript's socket functions: real TCP connections from the program to a client's host and port.

A program opens named sockets (`socket_open("127.0.0.1", 50002, "reverse_socket")`), sends
ints (4 bytes, big-endian), bytes and strings, and reads binary integers, bytes, ASCII floats or
text with a time-out; socket_set_var and socket_get_var are the "SET name value" / "GET name"
requests Robotiq's gripper preambles make. Every socket is non-blocking: a read or a connect
waits for its thread's next control steps, never the control loop, and a socket's buffer is
bounded. Only IP addresses are accepted (no name look-ups from a control step). The program's
sockets close with it.

Reads take the records in order, as the Script Manual says, and each read takes all that has
come (up to MAX_BUFFER held): a record already there costs no control step. A client that
writes faster than the program reads (URCL's examples write without pacing) fills the buffer;
that is said once in the log, since the program then acts on old records (docs/decisions.md).
"""

from __future__ import annotations

import errno
import ipaddress
import logging
import re
import select
import socket
import struct
from collections.abc import Callable, Generator
from typing import Any

from rtde_spec.emulator.urscript.calls import arg, number, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt

log = logging.getLogger("rtde_spec.emulator")
MAX_BUFFER = 1 << 20  # bytes a socket keeps unread
OPEN_TIMEOUT = 2.0  # s a socket_open waits for the connection
REPLY_TIMEOUT = 2.0  # s socket_get_var waits for its reply
DEFAULT = "socket_0"
Args = list[Any]
Kwargs = dict[str, Any]
Waiting = Generator[None, None, Any]


class ProgramSocket:
    """One named connection and what has arrived on it, unread."""

    def __init__(self, sock: socket.socket, name: str = DEFAULT) -> None:
        self.sock, self.buffer, self.closed, self.name = sock, bytearray(), False, name
        self.behind = False  # the buffer was full: said once

    def pump(self) -> None:
        """Take what arrived (up to MAX_BUFFER), without waiting."""
        while not self.closed and len(self.buffer) < MAX_BUFFER:
            try:
                data = self.sock.recv(min(65536, MAX_BUFFER - len(self.buffer)))
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self.closed = True
                return
            if not data:
                self.closed = True
                return
            self.buffer += data
        if len(self.buffer) >= MAX_BUFFER and not self.behind:
            self.behind = True
            log.warning(
                "program socket %r: %d kB unread, its client writes faster than the program reads "
                "(records are read in order: the program acts on old ones)",
                self.name,
                MAX_BUFFER >> 10,
            )

    def send(self, data: bytes) -> bool:
        try:
            self.sock.sendall(data)  # small writes on a local link; a full buffer is a failure
        except (BlockingIOError, OSError):
            return False
        return True

    def close(self) -> None:
        self.closed = True
        self.sock.close()


def sockets_of(runner: Runner) -> dict[str, ProgramSocket]:
    table = getattr(runner, "sockets", None)
    if table is None:
        table = {}
        runner.sockets = table  # type: ignore[attr-defined]
    return table


def opening_of(runner: Runner) -> set[socket.socket]:
    """The sockets whose socket_open is still waiting for the connection."""
    pending = getattr(runner, "opening", None)
    if pending is None:
        pending = set()
        runner.opening = pending  # type: ignore[attr-defined]
    return pending


def close_all(runner: Runner) -> None:
    """The program's sockets, and those it is still opening: a connection the client already
    accepted must close with the program, or the client never learns the program ended (URCL's
    reverse interface stayed connected after `stop program` came during its socket_open)."""
    for sock in sockets_of(runner).values():
        sock.close()
    sockets_of(runner).clear()
    for pending in opening_of(runner):
        pending.close()
    opening_of(runner).clear()


def _name(stmt: Stmt, args: Args, kwargs: Kwargs, index: int) -> str:
    name = arg(stmt, args, kwargs, index, "socket_name", DEFAULT)
    if not isinstance(name, str):
        raise ScriptFault(f"{stmt.name}: socket_name must be a string, not {type_name(name)}", stmt.line, 1)
    return name


def socket_open(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Waiting:
    address, port = arg(stmt, args, kwargs, 0, "address"), arg(stmt, args, kwargs, 1, "port")
    name = _name(stmt, args, kwargs, 2)
    try:
        ipaddress.ip_address(address)
    except ValueError:
        return _done(False)  # a host name: the emulator looks up no names
    if not isinstance(port, int) or not 0 < port < 65536:
        raise ScriptFault(f"socket_open: no port {port!r}", stmt.line, 1)
    table = sockets_of(runner)
    if name in table:
        table.pop(name).close()
    try:
        sock = socket.socket(socket.AF_INET6 if ":" in address else socket.AF_INET, socket.SOCK_STREAM)
    except OSError:  # out of file descriptors: the program's socket_open fails, as on a controller
        return _done(False)
    sock.setblocking(False)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    code = sock.connect_ex((address, port))
    opening_of(runner).add(sock)
    return _connecting(runner, name, sock, code, runner.clock + OPEN_TIMEOUT)


def _connecting(runner: Runner, name: str, sock: socket.socket, code: int, until: float) -> Waiting:
    while code != 0:
        if code not in (errno.EINPROGRESS, errno.EALREADY, errno.EWOULDBLOCK) or runner.clock >= until:
            opening_of(runner).discard(sock)
            sock.close()
            return False
        yield  # the connection comes while the control steps go on
        if sock.fileno() < 0:
            return False  # the program ended meanwhile: close_all closed it
        _, writable, _ = select.select([], [sock], [], 0)
        if writable:
            code = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR) or 0
            if code in (errno.EINPROGRESS, errno.EALREADY):
                code = errno.ECONNREFUSED
    opening_of(runner).discard(sock)
    sockets_of(runner)[name] = ProgramSocket(sock, name)
    return True


def _done(value: Any) -> Waiting:
    return value
    yield  # a generator that returns at once


def socket_close(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    sock = sockets_of(runner).pop(_name(stmt, args, kwargs, 0), None)
    if sock is not None:
        sock.close()


def _sender(encode: Callable[[Stmt, Any], bytes]) -> Callable[[Runner, Stmt, Args, Kwargs], bool]:
    def send(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
        data = encode(stmt, arg(stmt, args, kwargs, 0, "value"))
        sock = sockets_of(runner).get(_name(stmt, args, kwargs, 1))
        return sock is not None and not sock.closed and sock.send(data)

    return send


def _int(stmt: Stmt, value: Any) -> bytes:
    if not isinstance(value, int) or isinstance(value, bool):
        raise ScriptFault(f"{stmt.name}: value must be an int, not {type_name(value)}", stmt.line, 1)
    return struct.pack(">i", value)


def _text(stmt: Stmt, value: Any) -> bytes:
    from rtde_spec.emulator.urscript.calls import to_str

    return (to_str(value) + ("\n" if stmt.name == "socket_send_line" else "")).encode()


def _byte(stmt: Stmt, value: Any) -> bytes:
    return bytes([int(number(stmt, value, "value")) & 0xFF])


SENDERS = {
    "socket_send_int": _sender(_int),
    "socket_send_string": _sender(_text),
    "socket_send_line": _sender(_text),
    "socket_send_byte": _sender(_byte),
}


def _reader(take: Callable[[ProgramSocket, int], list[Any] | None]) -> Callable[..., Waiting]:
    def read(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Waiting:
        count = arg(stmt, args, kwargs, 0, "number")
        if not isinstance(count, int) or not 0 < count <= 30:
            raise ScriptFault(f"{stmt.name}: number must be 1 to 30, not {count!r}", stmt.line, 1)
        sock = sockets_of(runner).get(_name(stmt, args, kwargs, 1))
        timeout = number(stmt, arg(stmt, args, kwargs, 2, "timeout", 2.0), "timeout")
        return _reading(runner, sock, take, count, timeout)

    return read


def _reading(
    runner: Runner, sock: ProgramSocket | None, take: Callable[[ProgramSocket, int], list[Any] | None],
    count: int, timeout: float,
) -> Waiting:  # fmt: skip
    until = runner.clock + timeout
    failed = [0] + [-1] * count if take in (_binary, _bytes) else [0] + [0.0] * count
    used = getattr(runner, "slice_used", None)
    if used is not None and used():
        yield  # the thread's share of the step is spent: it reads after the other threads' turns
    while sock is not None:
        sock.pump()
        got = take(sock, count)
        if got is not None:
            return got
        if sock.closed or (timeout > 0 and runner.clock >= until):
            break
        yield
    return failed


def _binary(sock: ProgramSocket, count: int) -> list[Any] | None:
    size = 4 * count
    if len(sock.buffer) < size:
        return None
    values = list(struct.unpack(f">{count}i", sock.buffer[:size]))
    del sock.buffer[:size]
    return [count, *values]


_ASCII = re.compile(rb"\(([^()]*)\)")


def _ascii(sock: ProgramSocket, count: int) -> list[Any] | None:
    found = _ASCII.search(sock.buffer)
    if found is None:
        return None
    text = bytes(found.group(1))  # before the buffer changes under the match
    del sock.buffer[: found.end()]
    try:
        values = [float(v) for v in text.split(b",")]
    except ValueError:
        return [0] + [0.0] * count
    return [len(values), *values] if len(values) == count else [0] + [0.0] * count


def _bytes(sock: ProgramSocket, count: int) -> list[Any] | None:
    if len(sock.buffer) < count:
        return None
    values = list(sock.buffer[:count])
    del sock.buffer[:count]
    return [count, *values]


READERS = {
    "socket_read_binary_integer": _reader(_binary),
    "socket_read_ascii_float": _reader(_ascii),
    "socket_read_byte_list": _reader(_bytes),
}


# --- the text requests URCaps' preambles use (Robotiq's grippers: SET ACT 1, GET STA) ---------------

MAX_STRING = 1024  # characters socket_read_string returns at most, its terminators included
_ESCAPES = {"\\n": "\n", "\\r": "\r", "\\t": "\t"}


def _text_arg(stmt: Stmt, value: Any, name: str) -> str:
    if not isinstance(value, str):
        raise ScriptFault(f"{stmt.name}: {name} must be a string, not {type_name(value)}", stmt.line, 1)
    return value


def socket_set_var(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> None:
    """Send "SET <name> <value>\\n"; no reply is read."""
    name = _text_arg(stmt, arg(stmt, args, kwargs, 0, "name"), "name")
    value = arg(stmt, args, kwargs, 1, "value")
    if not isinstance(value, int) or isinstance(value, bool):
        value = int(number(stmt, value, "value"))  # the manual sends an int
    sock = sockets_of(runner).get(_name(stmt, args, kwargs, 2))
    if sock is not None and not sock.closed:
        sock.send(f"SET {name} {value}\n".encode("latin-1", "replace"))


def socket_get_var(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Waiting:
    """Send "GET <name>\\n" and read the reply line "<name> <int>" within 2 s; 0 on a time-out or a
    reply that is not that (the line is taken all the same)."""
    name = _text_arg(stmt, arg(stmt, args, kwargs, 0, "name"), "name")
    sock = sockets_of(runner).get(_name(stmt, args, kwargs, 1))
    if sock is None or sock.closed or not sock.send(f"GET {name}\n".encode("latin-1", "replace")):
        return _done(0)
    return _get_var(runner, sock, name)


def _get_var(runner: Runner, sock: ProgramSocket, name: str) -> Waiting:
    line = yield from _reading(runner, sock, _line, 1, REPLY_TIMEOUT)
    parts = bytes(line[1]).split() if line[0] else []
    if len(parts) == 2 and parts[0].decode("latin-1") == name and parts[1].lstrip(b"-").isdigit():
        return int(parts[1])
    return 0


def _line(sock: ProgramSocket, count: int) -> list[Any] | None:
    end = sock.buffer.find(b"\n")
    if end < 0:
        return None
    line = bytes(sock.buffer[:end]).rstrip(b"\r")
    del sock.buffer[: end + 1]
    return [1, line]


def socket_read_string(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Waiting:
    """What has come as text, or the text between prefix and suffix; "" on a time-out."""
    sock = sockets_of(runner).get(_name(stmt, args, kwargs, 0))
    prefix = _text_arg(stmt, arg(stmt, args, kwargs, 1, "prefix", ""), "prefix").lstrip(" ")
    suffix = _text_arg(stmt, arg(stmt, args, kwargs, 2, "suffix", ""), "suffix").lstrip(" ")
    if arg(stmt, args, kwargs, 3, "interpret_escape", False) is True:
        for escape, char in _ESCAPES.items():
            prefix, suffix = prefix.replace(escape, char), suffix.replace(escape, char)
    timeout = number(stmt, arg(stmt, args, kwargs, 4, "timeout", 2.0), "timeout")
    start, end = prefix.encode("latin-1", "replace"), suffix.encode("latin-1", "replace")

    def take(sock: ProgramSocket, count: int) -> list[Any] | None:
        buffer, begin = sock.buffer, 0
        if start:  # what comes before the prefix's end is dropped, once the message is whole
            found = buffer.find(start)
            if found < 0:
                return None
            begin = found + len(start)
        if end:
            stop = buffer.find(end, begin)
            if stop < 0:
                return None
            text = bytes(buffer[begin:stop])
            del buffer[: stop + len(end)]  # what follows the suffix stays
        elif len(buffer) > begin:
            text = bytes(buffer[begin : begin + MAX_STRING])
            del buffer[: begin + MAX_STRING]
        else:
            return None
        return [1, text[:MAX_STRING].decode("latin-1")]

    got = yield from _reading(runner, sock, take, 1, timeout)
    return got[1] if got[0] else ""


def socket_read_line(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> Waiting:
    """Deprecated (socket_read_string replaces it): the text up to the first "\\n" or "\\r\\n",
    which is dropped and not returned; "" on a time-out (a timeout of 0 or less waits for ever)."""
    sock = sockets_of(runner).get(_name(stmt, args, kwargs, 0))
    timeout = number(stmt, arg(stmt, args, kwargs, 1, "timeout", 2.0), "timeout")

    def take(sock: ProgramSocket, count: int) -> list[Any] | None:
        stop = sock.buffer.find(b"\n", 0, MAX_STRING)
        if stop < 0:
            if len(sock.buffer) < MAX_STRING:
                return None
            stop = MAX_STRING - 1  # a line longer than a string holds: its first part
        text = bytes(sock.buffer[:stop]).removesuffix(b"\r")
        del sock.buffer[: stop + 1]
        return [1, text.decode("latin-1")]

    got = yield from _reading(runner, sock, take, 1, timeout)
    return got[1] if got[0] else ""


READERS["socket_read_line"] = socket_read_line
