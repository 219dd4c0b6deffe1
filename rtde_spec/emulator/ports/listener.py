"""The emulator's listening ports, which keep serving when the process runs out of file descriptors.

asyncio's own accept loop (Python 3.11) answers an accept() refused with EMFILE by logging a
traceback for each of up to 100 retries at once and trying again a second later, over and over,
while the client waits in the kernel's queue for a reply that never comes. Here each port
accepts in a task of its own; out of descriptors, the connection waiting is accepted on a
descriptor held in reserve and closed at once (libuv's "EMFILE trick"), so its client hears
at once, and the clients connected keep being served. One line is logged when the limit is
hit and one when a connection is accepted again; the limit is never raised.
"""

from __future__ import annotations

import asyncio
import errno
import logging
import math
import os
import socket
import time
from collections.abc import Callable

try:  # at import: out of descriptors, importing it then would fail too
    import resource
except ImportError:  # not POSIX
    resource = None  # type: ignore[assignment]

log = logging.getLogger("rtde_spec.emulator")

OUT_OF_DESCRIPTORS = frozenset({errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM})
# a client gone (or refused by a firewall) between connecting and accept(): nothing to do
GONE = frozenset({errno.ECONNABORTED, errno.ECONNRESET, errno.EPROTO, errno.EPERM, errno.EINTR, errno.EAGAIN})
RETRY_SECONDS = 0.5  # with no descriptor in reserve, how often a port short of them tries again
QUIET_SECONDS = 60.0  # running out is logged at most this often (a port at its limit flaps)
REFUSE_BATCH = 64  # connections refused in one go, so a flood cannot hold the loop up
BACKLOG = 100  # as asyncio's create_server


def descriptor_limit() -> str:
    """The process's soft limit on open files, as `ulimit -n` says it ("?" where unknown)."""
    if resource is None:
        return "?"
    try:
        soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    except (OSError, ValueError):
        return "?"
    return "unlimited" if soft == resource.RLIM_INFINITY else str(soft)


class Descriptors:
    """What the ports share about the process's file descriptors: one held in reserve, to accept
    and close a connection with when none is left, and whether they ran out (logged once)."""

    def __init__(self) -> None:
        self._reserve: int | None = None
        self.short = False  # the last accept() failed for want of a descriptor
        self.refused = 0  # connections closed unserved for want of a descriptor, in all
        self._refused_since = 0  # ... since running out was last logged
        self._announced = False  # running out was logged and getting them back is not yet
        self._warned_at = -math.inf

    def hold(self) -> None:
        """Open the reserve if none is held; with no descriptor free it is tried again later."""
        if self._reserve is None:
            try:
                self._reserve = os.open(os.devnull, os.O_RDONLY | getattr(os, "O_CLOEXEC", 0))
            except OSError:
                pass

    def start(self) -> None:
        """Take the reserve as the ports open; none free already: say so now, not at the first client."""
        self.hold()
        if self._reserve is None:
            self.short = self._announced = True
            self._warned_at = time.monotonic()
            log.warning(
                "serve: out of file descriptors already (ulimit -n %s); clients wait until one closes",
                descriptor_limit(),
            )

    def release(self) -> None:
        """Close the reserve (the emulator stops)."""
        if self._reserve is not None:
            os.close(self._reserve)
            self._reserve = None

    def refuse(self, sock: socket.socket) -> int:
        """Accept and close the connections waiting on `sock` on the reserve's descriptor; how many
        (0: no reserve, or another thread took the descriptor first). The reserve is then reopened."""
        if self._reserve is None:
            return 0
        os.close(self._reserve)
        self._reserve = None
        count = 0
        try:
            for _ in range(REFUSE_BATCH):
                try:
                    conn, _ = sock.accept()
                except (BlockingIOError, InterruptedError):
                    break
                except OSError as exc:
                    if exc.errno in GONE:
                        continue
                    break
                conn.close()
                count += 1
        finally:
            self.hold()
        self.refused += count
        self._refused_since += count
        return count

    def ran_out(self, port: int, refused: int) -> None:
        """An accept() on `port` failed for want of a descriptor: one line, the first time."""
        if self.short:
            return
        self.short = True
        now = time.monotonic()
        if now - self._warned_at < QUIET_SECONDS:
            return
        self._warned_at = now
        self._announced = True
        fate = "refused" if refused else "left waiting"
        log.warning(
            "serve: out of file descriptors (ulimit -n %s); connections on port %d %s until one closes",
            descriptor_limit(),
            port,
            fate,
        )

    def accepted(self, port: int) -> None:
        """A connection on `port` was accepted: descriptors are free again (logged if running out was)."""
        if self.short:
            self.short = False
            if self._announced:
                self._announced = False
                log.info(
                    "serve: file descriptors free again: port %d accepts connections (%d refused meanwhile)",
                    port,
                    self._refused_since,
                )
                self._refused_since = 0
        self.hold()


class Listener:
    """One port's listening sockets and the tasks accepting on them (what asyncio's Server was)."""

    def __init__(
        self, sockets: list[socket.socket], factory: Callable[[], asyncio.Protocol], descriptors: Descriptors
    ) -> None:
        self.sockets = sockets
        self._factory = factory
        self._descriptors = descriptors
        self._logged: set[str] = set()  # the unexpected errors logged already (each once)
        self._readiness = True  # wait for a connection, then accept(): False where the loop cannot
        loop = asyncio.get_running_loop()
        self._tasks = [loop.create_task(self._accept(sock)) for sock in sockets]

    @classmethod
    async def open(
        cls, host: str, port: int, factory: Callable[[], asyncio.Protocol], descriptors: Descriptors
    ) -> Listener:
        """Listen on host:port (0: a free port) as asyncio's create_server binds: every address
        `host` stands for, SO_REUSEADDR, IPv6 sockets IPv6 only; OSError as it words it."""
        loop = asyncio.get_running_loop()
        infos = await loop.getaddrinfo(
            host, port, family=socket.AF_UNSPEC, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
        )
        sockets: list[socket.socket] = []
        try:
            for family, kind, proto, _, address in dict.fromkeys(infos):
                try:
                    sock = socket.socket(family, kind, proto)
                except OSError:
                    continue  # as asyncio: e.g. IPv6 named but not supported
                sockets.append(sock)
                if os.name == "posix":
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                if family == socket.AF_INET6 and hasattr(socket, "IPPROTO_IPV6"):
                    sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
                try:
                    sock.bind(address)
                except OSError as err:
                    why = (err.strerror or str(err)).lower()
                    msg = f"error while attempting to bind on address {address!r}: {why}"
                    raise OSError(err.errno, msg) from None
                sock.listen(BACKLOG)
                sock.setblocking(False)
            if not sockets:
                raise OSError(errno.EADDRNOTAVAIL, f"no address to listen on for {host!r}")
        except BaseException:
            for sock in sockets:
                sock.close()
            raise
        return cls(sockets, factory, descriptors)

    @property
    def port(self) -> int:
        return int(self.sockets[0].getsockname()[1])

    def close(self) -> None:
        """Stop accepting and close the listening sockets (connections made are the caller's)."""
        loop = asyncio.get_running_loop()
        for task in self._tasks:
            task.cancel()
        for sock in self.sockets:
            if sock.fileno() >= 0:
                try:
                    loop.remove_reader(sock.fileno())  # before close: its number may be reused at once
                except NotImplementedError:
                    pass
                sock.close()

    async def wait_closed(self) -> None:
        await asyncio.gather(*self._tasks, return_exceptions=True)

    async def _accept(self, sock: socket.socket) -> None:
        """Accept and serve connections until closed; nothing raised ends it."""
        loop = asyncio.get_running_loop()
        port = int(sock.getsockname()[1])
        while True:
            try:
                conn = await self._next(loop, sock)
            except OSError as exc:
                await self._failed(sock, port, exc)
                continue
            except asyncio.CancelledError:
                raise
            except Exception as exc:  # a surprise: logged once, accepting goes on
                self._once(port, exc)
                await asyncio.sleep(RETRY_SECONDS)
                continue
            self._descriptors.accepted(port)
            try:
                await loop.connect_accepted_socket(self._factory, conn)
            except asyncio.CancelledError:
                conn.close()
                raise
            except Exception as exc:
                conn.close()
                self._once(port, exc)

    async def _next(self, loop: asyncio.AbstractEventLoop, sock: socket.socket) -> socket.socket:
        """The next connection on `sock`. Linux's accept() fails with EMFILE even when none waits,
        so a port waits for one first: out of descriptors, only a port with a client is short."""
        if self._readiness:
            try:
                await _readable(loop, sock)
            except NotImplementedError:  # a proactor loop: its sock_accept waits
                self._readiness = False
            else:
                conn, _ = sock.accept()
                conn.setblocking(False)
                return conn
        conn, _ = await loop.sock_accept(sock)
        return conn

    async def _failed(self, sock: socket.socket, port: int, exc: OSError) -> None:
        """After a failed accept(): out of descriptors, refuse what waits (or wait for one to free)."""
        if exc.errno in OUT_OF_DESCRIPTORS:
            refused = self._descriptors.refuse(sock)
            self._descriptors.ran_out(port, refused)
            if not refused:
                await asyncio.sleep(RETRY_SECONDS)  # no reserve: the client waits; no spinning meanwhile
        elif exc.errno not in GONE:
            self._once(port, exc)
            await asyncio.sleep(RETRY_SECONDS)

    def _once(self, port: int, exc: BaseException) -> None:
        """Log an unexpected failure to accept or serve, once per kind, with no traceback."""
        what = f"{type(exc).__name__}: {exc}"
        if what not in self._logged:
            self._logged.add(what)
            log.warning("serve: port %d: a connection not served (%s); accepting goes on", port, what)


async def _readable(loop: asyncio.AbstractEventLoop, sock: socket.socket) -> None:
    """Return when `sock` has a connection waiting (or an error) to accept."""
    waiter: asyncio.Future[None] = loop.create_future()

    def ready() -> None:
        if not waiter.done():
            waiter.set_result(None)

    fd = sock.fileno()
    loop.add_reader(fd, ready)
    try:
        await waiter
    finally:
        if sock.fileno() == fd:  # closed (Listener.close), its number may be another's by now
            loop.remove_reader(fd)
