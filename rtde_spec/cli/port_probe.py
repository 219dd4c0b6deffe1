"""What listens on a port, told from its first bytes: for `record` and `watch` pointed at the wrong one.

Called only after a handshake failed or timed out, so the happy path never pays for it.
Each interface gives itself away without a request, or with the cheapest one:
- primary/secondary ports send a Version message unprompted on connect;
- the dashboard server greets with a line ("Connected: Universal Robots Dashboard Server");
- the real-time ports send fixed-size packages unprompted, each led by its length;
- an RTDE port sends nothing until asked, and answers a protocol version request.
"""

from __future__ import annotations

import functools
import socket
import struct
import time
from dataclasses import dataclass
from typing import Any

from rtde_spec._generated.constants import PRIMARY_PORTS, RTDE_PORT

FIRST_BYTES_WAIT = 1.0  # seconds a port may take to speak first (a Version message comes at once)


@dataclass(frozen=True)
class PortKind:
    """kind: rtde, primary, dashboard, realtime, closed, unresolved, silent or unknown; detail: what
    showed it."""

    kind: str
    detail: str


def probe(host: str, port: int, timeout: float = 2.0) -> PortKind:
    """Connect once and tell which interface answers on host:port (never raises for the port's sake)."""
    try:
        sock = socket.create_connection((host, port), timeout=min(timeout, 3.0))
    except OSError as exc:
        return unreachable(host, exc)
    with sock:
        head = _read_for(sock, min(timeout, FIRST_BYTES_WAIT))
        if head:
            return _unprompted(head)
        if _peer_closed(sock):
            return _REFUSED
        return _rtde_answer(sock, min(timeout, 3.0))


_REFUSED = PortKind(
    "refused",
    "the server closed the connection at once, unread: at its client limit, or out of file descriptors",
)


def _peer_closed(sock: socket.socket) -> bool:
    """Whether the peer has closed its side (an end of stream waits), without waiting."""
    try:
        return sock.recv(1, socket.MSG_PEEK | getattr(socket, "MSG_DONTWAIT", 0)) == b""
    except (BlockingIOError, InterruptedError, TimeoutError):
        return False
    except OSError:  # reset by the peer: closed as well
        return True


def unreachable(host: str, exc: OSError) -> PortKind:
    """Why connecting failed, in plain words: a name that does not resolve is not a closed port."""
    if isinstance(exc, socket.gaierror):
        return PortKind(
            "unresolved",
            f"the name {host!r} does not resolve to an address ({exc.strerror or exc}); check its "
            "spelling, or give the controller's IP address to --host",
        )
    return PortKind("closed", f"nothing accepts connections there ({exc.strerror or exc})")


def _read_for(sock: socket.socket, seconds: float, limit: int = 8192) -> bytes:
    """What the peer sends within `seconds` (up to `limit` bytes), without sending anything."""
    data = b""
    deadline = time.monotonic() + seconds
    while len(data) < limit:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        sock.settimeout(left)
        try:
            piece = sock.recv(limit - len(data))
        except (TimeoutError, OSError):
            break
        if not piece:
            break
        data += piece
        if len(data) >= 64 and _enough(data):
            break
    return data


def _enough(data: bytes) -> bool:
    """Whether the bytes so far already tell the interface (saves waiting the full second)."""
    return (
        data.startswith(_greeting().encode())
        or _primary_version(data) is not None
        or (_realtime_size(data) is not None)
    )


def _unprompted(head: bytes) -> PortKind:
    greeting = _greeting()
    if head.startswith(greeting.encode()):
        return PortKind("dashboard", f"it greeted with {greeting!r}")
    version = _primary_version(head)
    if version is not None:
        return PortKind("primary", f"it sent a Version message unprompted: {version}")
    size = _realtime_size(head)
    if size is not None:
        return PortKind("realtime", f"it sends {size}-byte packages unprompted, like the real-time interface")
    return PortKind("unknown", f"it sent {len(head)} bytes unprompted that no UR interface starts with "
                    f"(first: {head[:16].hex(' ')})")  # fmt: skip


@functools.cache
def _greeting() -> str:
    from rtde_spec.metamodel.dashboard import dashboard_spec

    return dashboard_spec().greeting


def _primary_version(head: bytes) -> str | None:
    """'controller 5.15.0' when the bytes start with a primary/secondary Version message."""
    from rtde_spec.errors import RtdeSpecError
    from rtde_spec.primary.codec import PrimaryStreamDecoder

    decoder = PrimaryStreamDecoder()
    try:
        messages = decoder.feed(head)
    except RtdeSpecError:
        return None
    if not messages or getattr(messages[0][1], "NAME", None) != "version_message":
        return None
    return f"controller {decoder.version}" if decoder.version is not None else "a controller"


def _realtime_size(head: bytes) -> int | None:
    """The package size when the bytes are two or more equal-sized packages, each led by its length."""
    if len(head) < 4:
        return None
    (size,) = struct.unpack_from(">i", head)
    if not 8 <= size <= 65536 or len(head) < size + 4:
        return None
    (again,) = struct.unpack_from(">i", head, size)
    return size if again == size else None


def _rtde_answer(sock: socket.socket, timeout: float) -> PortKind:
    """Ask for RTDE protocol 2, as every RTDE client starts: an RTDE port answers it."""
    from rtde_spec.errors import RtdeSpecError
    from rtde_spec.rtde.codec import build, decode

    try:
        sock.sendall(build("request_protocol_version", protocol_version=2))
    except OSError:
        return PortKind("silent", "it accepts connections but closed on a request")
    reply = _read_for(sock, timeout, limit=3)
    if len(reply) == 3:
        (size,) = struct.unpack_from(">H", reply)
        reply += _read_for(sock, timeout, limit=max(size - 3, 0))
    try:
        message = decode(reply, sender="controller", protocol_version=2)
    except RtdeSpecError:
        message = None
    if message is not None and message.NAME == "request_protocol_version_reply":
        return PortKind("rtde", "it answered an RTDE protocol version request")
    if reply:
        return PortKind("unknown", f"it answered an RTDE request with {reply[:16].hex(' ')}, not RTDE")
    if _peer_closed(sock):
        return _REFUSED
    return PortKind("silent", f"it sends nothing and did not answer an RTDE request within {timeout:g} s")


def _where_rtde() -> str:
    return f"RTDE is on port {RTDE_PORT} (--port {RTDE_PORT})"


def _where_primary() -> str:
    ports = ", ".join(f"{p} ({n.replace('_', ' ')})" for n, p in PRIMARY_PORTS.items())
    return f"the primary/secondary interface is on ports {ports}; e.g. --port {PRIMARY_PORTS['secondary']}"


NAMES = {
    "rtde": "RTDE",
    "primary": "the primary/secondary interface",
    "dashboard": "the dashboard server",
    "realtime": "a real-time interface",
}


def wrong_port(host: str, port: int, wanted: str, timeout: float = 2.0) -> str | None:
    """A sentence saying what listens on host:port when it is not `wanted` ('rtde' or 'primary'), and
    where `wanted` is; None when the port does speak `wanted` (the failure was something else)."""
    found = probe(host, port, timeout)
    if found.kind == wanted:
        return None
    where = _where_rtde() if wanted == "rtde" else _where_primary()
    if found.kind in NAMES:
        return f"{host}:{port} speaks {NAMES[found.kind]} ({found.detail}), not {NAMES[wanted]}: {where}"
    if found.kind == "unresolved":
        return f"--host {host}: {found.detail}"
    if found.kind == "closed":
        return f"{host}:{port}: {found.detail}; check --host and --port: {where}"
    if found.kind == "refused":  # it may well speak `wanted`: it served no one just now
        return f"{host}:{port}: {found.detail}; try again once another client has left"
    return f"{host}:{port} does not speak {NAMES[wanted]}: {found.detail}; {where}"


def handshake_error(args: Any, wanted: str, exc: BaseException) -> BaseException:
    """What `record`/`watch` raise when connecting to --host/--port failed: the port's real
    protocol when it speaks another one (an RtdeConnectionError), else the failure itself."""
    from rtde_spec.errors import RtdeConnectionError

    hint = wrong_port(args.host, args.port, wanted, min(args.timeout, 2.0))
    if hint is None:
        return exc
    error = RtdeConnectionError(hint)
    error.__cause__ = exc
    return error
