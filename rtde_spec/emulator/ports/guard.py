"""Per-client limits of the emulator's ports, so one client never costs the others.

A hostile or broken client gets bounded memory and time: what it has sent that makes
no whole package (or script, or command line) yet is held up to a limit; a package it
began must be finished within a time-out; an RTDE client must send its first package
soon after connecting; what is queued for a client that stopped reading is bounded;
each port takes a limited number of clients. A client over a limit is dropped with
one log line (WARNING) naming it and why, as a controller closes such a connection. A stream
whose client may rightly never read (`skips_when_behind`: the real-time port, where ur_rtde's
script client only sends) misses messages instead, its queue kept at the limit.
A client that is connected and only reads (a primary-port monitor, a dashboard
client between commands) is never dropped for being quiet unless `idle_timeout` is set.
"""

from __future__ import annotations

import asyncio
import logging
import time
from dataclasses import dataclass

log = logging.getLogger("rtde_spec.emulator")
CLOSE_GRACE = 1.0  # s a dropped client's last words (an error text) may take before the socket is cut


@dataclass
class ClientLimits:
    """What one client may cost; every emulator port applies them."""

    max_clients: int = 32  # per port; a further connection is closed at once
    max_input_bytes: int = 1 << 20  # bytes held that make no whole package, script or line yet
    max_send_backlog: int = 4 << 20  # bytes queued for a client that stopped reading
    handshake_timeout: float | None = 30.0  # s from connecting to the first whole RTDE package
    stall_timeout: float | None = 10.0  # s a package, script or line begun may stay unfinished
    idle_timeout: float | None = None  # s without any bytes from the client (off: readers never send)
    max_bad_messages: int = 64  # packages refused as undecodable before the client is dropped


class Port:
    """The connections of one listening port, under one set of limits."""

    def __init__(self, name: str, limits: ClientLimits) -> None:
        self.name, self.limits = name, limits
        self.connections: set[GuardedConnection] = set()
        self.refused = 0
        self.dropped = 0

    def check(self, now: float) -> None:
        """Drop every client over a time or backlog limit (called a few times a second)."""
        for conn in list(self.connections):
            conn.check(now)


class GuardedConnection(asyncio.Protocol):
    """A connection that keeps its port's limits; subclasses say what they hold with `received`."""

    needs_handshake = False  # an RTDE client must send a whole package within handshake_timeout
    skips_when_behind = False  # a client that stopped reading misses messages instead of being dropped

    def __init__(self, port: Port) -> None:
        self.port = port
        self.limits = port.limits
        self.transport: asyncio.Transport | None = None
        self.peer = "?"
        self.admitted = False
        self.dropped = False
        now = time.monotonic()
        self.connected_at = self.last_input = now
        self.partial_since: float | None = None  # when the unfinished package held now was begun
        self.pending = 0
        self.handshaken = not self.needs_handshake
        self.bad_messages = 0
        self.behind = False  # (skips_when_behind) its messages are being skipped
        self.skipped = 0

    # --- asyncio ------------------------------------------------------------

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.transport = transport
        self.peer = str(transport.get_extra_info("peername"))
        if len(self.port.connections) >= self.limits.max_clients:
            self.port.refused += 1
            self.dropped = True
            log.warning(
                "refusing %s client %s: %d clients connected, the port's limit",
                self.port.name,
                self.peer,
                len(self.port.connections),
            )
            transport.abort()
            return
        self.admitted = True
        self.port.connections.add(self)
        self.opened()

    def connection_lost(self, exc: Exception | None) -> None:
        if self.admitted:
            self.port.connections.discard(self)
            self.closed()

    def opened(self) -> None:
        """The client is admitted (hook)."""

    def closed(self) -> None:
        """The connection is gone (hook)."""

    # --- the limits ---------------------------------------------------------

    def received(self, pending: int, completed: int) -> bool:
        """After a read: `pending` bytes held make nothing whole yet, `completed` units were.

        False when the client is dropped for holding too much.
        """
        now = time.monotonic()
        self.last_input = now
        self.pending = pending
        if completed:
            self.handshaken = True
        if pending > self.limits.max_input_bytes:
            limit = self.limits.max_input_bytes
            self.drop(f"{pending} bytes sent that make no whole message (limit {limit})")
            return False
        if not pending:
            self.partial_since = None
        elif completed or self.partial_since is None:
            self.partial_since = now
        return True

    def refused_message(self, what: str) -> bool:
        """Count a message refused as bad; False when that was one too many and the client is dropped."""
        self.bad_messages += 1
        if self.bad_messages > self.limits.max_bad_messages:
            limit = self.limits.max_bad_messages
            self.drop(f"{self.bad_messages} bad messages (limit {limit}), the last: {what}")
            return False
        return True

    def check(self, now: float) -> None:
        reason = self._overdue(now)
        if reason is not None:
            self.drop(reason)

    def _overdue(self, now: float) -> str | None:
        lim = self.limits
        if not self.handshaken and lim.handshake_timeout is not None:
            if now - self.connected_at > lim.handshake_timeout:
                return f"no whole package within {lim.handshake_timeout:g} s of connecting"
        if self.partial_since is not None and lim.stall_timeout is not None:
            if now - self.partial_since > lim.stall_timeout:
                held = self.pending
                return f"a message begun {lim.stall_timeout:g} s ago is unfinished ({held} bytes held)"
        if lim.idle_timeout is not None and now - self.last_input > lim.idle_timeout:
            return f"nothing received for {lim.idle_timeout:g} s"
        backlog = self.backlog()
        if backlog > lim.max_send_backlog and not self.skips_when_behind:
            return f"it stopped reading ({backlog} bytes queued, limit {lim.max_send_backlog})"
        return None

    def backlog(self) -> int:
        return self.transport.get_write_buffer_size() if self.transport is not None else 0

    def drop(self, reason: str) -> None:
        """Close the connection with one log line; what is queued for it is freed."""
        if self.dropped or self.transport is None:
            return
        self.dropped = True
        self.port.dropped += 1
        log.warning("dropping %s client %s: %s", self.port.name, self.peer, reason)
        transport = self.transport
        if transport.get_write_buffer_size() <= 1 << 16:
            transport.close()  # what is queued (an error text) may still reach it, briefly
            asyncio.get_running_loop().call_later(CLOSE_GRACE, transport.abort)
        else:
            transport.abort()

    def write(self, data: bytes) -> bool:
        """Queue bytes for the client; a client this far behind is dropped instead."""
        transport = self.transport
        if transport is None or self.dropped or transport.is_closing():
            return False
        backlog = transport.get_write_buffer_size()
        limit = self.limits.max_send_backlog
        # one that fell behind resumes once half its queue is gone: a slow reader does not flap
        if self.skips_when_behind and (backlog > limit or (self.behind and backlog > limit // 2)):
            self._skip(backlog)
            return False
        if backlog > limit:
            self.drop(f"it stopped reading ({backlog} bytes queued, limit {limit})")
            return False
        if self.behind:
            self.behind = False
            log.info("%s client %s reads again (%d skipped)", self.port.name, self.peer, self.skipped)
        transport.write(data)
        return True

    def _skip(self, backlog: int) -> None:
        """A message not queued for a client that stopped reading: one log line when it falls behind."""
        self.skipped += 1
        if not self.behind:
            self.behind = True
            log.warning(
                "%s client %s stopped reading (%d bytes queued, limit %d): its messages are skipped "
                "until it reads again",
                self.port.name,
                self.peer,
                backlog,
                self.limits.max_send_backlog,
            )


def split_lines(buffer: bytearray, data: bytes) -> tuple[bytearray, list[bytearray]]:
    """`buffer` and `data` cut at each newline: what follows the last one (kept for the next read),
    and the whole lines before it (the line ports: dashboard, interpreter socket). Only `data` is
    searched until a line ends: on the interpreter socket a line held up to the port's input limit
    (1 MB), re-split on every read of 100 bytes, kept the server's loop busy for 6 s."""
    buffer += data
    if b"\n" not in data:
        return buffer, []
    lines = buffer.split(b"\n")
    return bytearray(lines.pop()), lines
