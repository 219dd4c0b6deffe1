"""What the blocking and asyncio RTDE clients share around the sans-I/O core: the address,
the data queue, the counters and the reader's wake-up mark (SO_RCVLOWAT)."""

from __future__ import annotations

import collections
import socket
from typing import Any

from rtde_spec._generated.constants import RTDE_PORT, RTDE_PROTOCOLS
from rtde_spec.endpoints import check_endpoint
from rtde_spec.errors import UsageError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.versions import Version
from rtde_spec.rtde.client_events import Reply
from rtde_spec.rtde.client_protocol import READ_SIZE, ClientProtocol

NOT_CONNECTED = "not connected: call connect() first, or use the client in a with block"
"""What receiving says before connect(): a usage error, not an end of data or a time-out."""


class ClientBase:
    """What the blocking and asyncio clients share: the address, the core, the queue, the counters."""

    def __init__(
        self,
        host: str,
        port: int = RTDE_PORT,
        *,
        timeout: float = 5.0,
        queue_size: int = 1000,
        batch: int = 1,
        catalogue: Catalogue | None = None,
    ) -> None:
        """`batch` > 1: the reader wakes once per that many data packages (less CPU per package,
        batch / frequency more latency): for recording and logging, not for control loops."""
        where = f"{host}:{port}"
        check_endpoint(host, port, timeout)
        if isinstance(batch, bool) or not isinstance(batch, int) or batch < 1:
            raise UsageError(f"batch must be an integer of at least 1, not {batch!r}", subject=where)
        self.host, self.port, self.timeout, self.batch = host, port, timeout, batch
        self.core = ClientProtocol(catalogue)
        self.skipped = 0
        self.received = 0
        self._data: collections.deque[Any] = collections.deque(maxlen=queue_size)
        self._closed: BaseException | None = None
        self._low_mark = 1  # SO_RCVLOWAT in force: bytes the reader waits for
        self._bufsize = READ_SIZE  # bytes a read asks for: what the socket holds, twice the low mark

    def _wake_after(self, sock: Any, size: int) -> None:
        """The reader wakes once `size` bytes wait (SO_RCVLOWAT); 1 restores per-package.

        Linux wakes a reader already blocked (or an event loop's poll) when the mark
        drops below what waits, so a reply after a request is never held back. Where
        the option is missing the client stays per package.
        """
        if sock is None or not hasattr(socket, "SO_RCVLOWAT"):
            return
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVLOWAT, size)
            self._low_mark = size
        except OSError:
            self._low_mark = 1
        self._bufsize = max(READ_SIZE, 2 * self._low_mark)

    @property
    def where(self) -> str:
        return f"{self.host}:{self.port}"

    @property
    def protocol_version(self) -> int:
        return self.core.state.version

    @property
    def controller_version(self) -> Version | None:
        return self.core.controller_version

    @property
    def connection_lost(self) -> BaseException | None:
        """Why the connection ended (None while it is open)."""
        return self._closed

    @staticmethod
    def _checked_reply(reply: Reply | BaseException) -> Reply:
        """The reply, or the error the reader or the controller's refusal handed over."""
        if isinstance(reply, BaseException):
            raise reply
        if reply.error is not None:
            raise reply.error
        return reply

    def _versions_to_try(self, protocol_version: int | None) -> list[int]:
        return [protocol_version] if protocol_version else sorted(RTDE_PROTOCOLS, reverse=True)
