"""A blocking RTDE client over the sans-I/O core, with a reader thread that never stops draining.

The controller drops a client that does not read; so from `connect()` a thread
reads the socket, hands replies to the caller waiting for them, logs text
messages, and keeps data packages in a bounded queue (oldest dropped, counted in
`skipped`). While the caller keeps asking for records (`receive`, `for record in
client`), it reads the socket itself and the reader thread steps aside (a lease of
`LEASE` seconds, renewed by every call): one wake-up per read instead of two and no
hand-over between threads; when the caller stops asking, the reader thread drains
again. Every blocking call has a timeout; refused and closed connections are
errors naming host and port. A connection that ends inside a package, a package that
does not decode or breaks the protocol, ends iteration with that error (a clean close
ends it quietly).
"""

from __future__ import annotations

import queue
import select
import socket
import struct
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from rtde_spec._generated.constants import RTDE_PORT
from rtde_spec.errors import ProtocolError, RtdeConnectionError, UsageError, require
from rtde_spec.recipes.codec import PAYLOAD_OFFSET
from rtde_spec.rtde.client_base import NOT_CONNECTED
from rtde_spec.rtde.client_protocol import READ_SIZE, InputRecipe, Reply
from rtde_spec.rtde.client_thread import ThreadReads, _new_tuple

LEASE = 0.2  # s: the reader thread keeps off the socket this long after the caller last read it
_END = object()  # what ends `for record in client` (the connection closed)
SLICE = 0.1  # s: a blocking read returns after this long without data (SO_RCVTIMEO), to look at the time


class RtdeClient(ThreadReads):
    """`with RtdeClient("192.168.1.10") as c: c.setup_outputs([...], 125); c.start(); for r in c: ...`"""

    def __init__(self, host: str, port: int = RTDE_PORT, **options: Any) -> None:
        super().__init__(host, port, **options)
        self._sock: socket.socket | None = None
        self._replies: queue.Queue[Reply | BaseException] = queue.Queue()
        self._callbacks: list[Callable[[Any], None]] = []
        self._raw_callbacks: list[Callable[[bytes], None]] = []
        self._batch_callbacks: list[Callable[[Any], None]] = []
        self._reader: threading.Thread | None = None
        self._send_lock = threading.Lock()
        self._closing = False  # close() was called: the end is ours, not the controller's
        self._reading = threading.Lock()  # held by the thread reading the socket (reader or caller)
        self._lease = 0.0  # monotonic time until which the caller's thread reads the socket
        self._nudge = threading.Event()  # wakes the reader thread out of a lease (close, a request)
        self._poll: Any = None  # the caller's poll object (select.poll objects are per thread)
        self._sliced = False  # SO_RCVTIMEO is SLICE: a read is one recv, no poll before it
        # the caller's reads land here (only while it holds `_reading`): no 64 kB bytes object
        # made and shrunk per read, ~3 µs of a package's CPU at 500 Hz on cold caches
        self._into = bytearray(READ_SIZE)
        self._view = memoryview(self._into)

    # --- connection ---------------------------------------------------------

    def connect(self, protocol_version: int | None = None) -> RtdeClient:
        """Connect, negotiate the newest protocol (falling back), and read the controller version.
        A client connects once (its recipes and state are that connection's): a new one reconnects."""
        if self._sock is not None:
            state = "was closed" if self._closing or self._closed is not None else "is connected"
            raise UsageError(
                f"this client {state}; make a new RtdeClient to connect again", subject=self.where
            )
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
        except OSError as exc:
            raise RtdeConnectionError(
                f"cannot connect to the RTDE port: {exc.strerror or exc}", subject=self.where
            ) from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock.settimeout(None)
        self._sliced = _recv_timeout(self._sock, SLICE)
        self._reader = threading.Thread(target=self._read_loop, name=f"rtde-reader-{self.where}", daemon=True)
        self._reader.start()
        try:
            for version in self._versions_to_try(protocol_version):
                reply = self._request(self.core.request_protocol_version(version))
                if reply.message.accepted:
                    break
            else:
                raise ProtocolError("the controller accepted no protocol version", subject=self.where)
            self._request(self.core.get_controller_version())
        except BaseException:  # no socket or reader thread left behind (`with` never reaches __exit__)
            self.close()
            raise
        return self

    def close(self) -> None:
        self._closing = True
        self._nudge.set()
        if self._sock is not None:
            try:
                self._sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
            self._sock.close()
        if self._reader is not None and self._reader is not threading.current_thread():
            self._reader.join(self.timeout)

    def __enter__(self) -> RtdeClient:
        return self.connect() if self._sock is None else self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- requests -----------------------------------------------------------

    def setup_outputs(self, names: Sequence[str] | str, frequency: float = 125.0) -> Any:
        """Subscribe to outputs (validated offline first); returns the recipe's codec."""
        self._request(self.core.setup_outputs(names, frequency))
        return self.core.output

    def setup_inputs(self, names: Sequence[str] | str) -> InputRecipe:
        self._request(self.core.setup_inputs(names))
        return self.core.inputs[max(self.core.inputs)]

    def start(self) -> None:
        if not self._request(self.core.start()).message.accepted:  # type: ignore[attr-defined]
            raise ProtocolError("the controller refused to start", subject=self.where)
        if self.batch > 1 and self.core.output is not None and hasattr(select, "poll"):
            self._wake_after(self._sock, self.batch * self.core.output.package_size)

    def pause(self) -> None:
        self._request(self.core.pause())

    def send(self, recipe: InputRecipe, values: Any = None, **named: Any) -> None:
        """Write inputs by field name: send(recipe, speed_slider_mask=1, speed_slider_fraction=0.5)."""
        self._write(self.core.send_inputs(recipe, values, named))

    def send_text(self, text: str, level: int = 3) -> None:
        self._write(self.core.text_message(text, level))

    # --- data ---------------------------------------------------------------

    def receive(self, timeout: float | None = None) -> Any:
        """The next output record (oldest first); TimeoutError when none arrives in time."""
        if self._callbacks or self._raw_callbacks or self._batch_callbacks:
            raise UsageError(
                "data packages go to the on_data/on_raw/on_batch callbacks, not to receive()",
                subject=self.where,
            )
        if self._data:
            try:
                return self._data.popleft()  # records waiting: no lock, no wait
            except IndexError:  # another caller took the last one
                pass
        asked = wait = self.timeout if timeout is None else timeout  # 0: what is there, no wait
        path = self.core.records_path
        if path is not None and self._sliced and wait >= SLICE and self._closed is None:
            # one read here if the socket is free: a record when it is one package (as __iter__)
            self._lease = time.monotonic() + LEASE
            if self._reading.acquire(False):
                try:
                    into = self._into
                    got = self._sock.recv_into(into)  # type: ignore[union-attr]
                    core = self.core
                    if got == path.size and into.startswith(path.lead) and core.aligned:
                        core.taken += got
                        self.received += 1
                        return _new_tuple(path.record_type, path.unpack(into, PAYLOAD_OFFSET))
                    self._other_read(bytes(self._view[:got]))
                except BlockingIOError:  # no data within SLICE
                    wait -= SLICE
                except OSError as exc:
                    self._finish(self._ended(f"connection lost: {exc.strerror or exc}"))
                finally:
                    self._reading.release()
        return self._wait(wait, asked)

    def _wait(self, wait: float, asked: float) -> Any:
        """The next record once it comes: read here when the socket is free, else wait for the
        reader thread's read to end (it hands the records over with the lock, then steps aside).
        `asked`: the caller's whole time-out, which the error names (`wait` is what is left)."""
        data = self._data
        now = time.monotonic()
        deadline = now + wait
        while True:
            if data:
                try:
                    return data.popleft()
                except IndexError:  # another caller took the last one
                    continue
            if self._closed is not None:
                raise self._gone()
            self._lease = now + LEASE  # the reader thread steps aside after its current read
            if self._reading.acquire(True, max(0.0, deadline - now)):
                try:
                    if self._closed is None and not data:
                        record = self._read_here(deadline - now)
                        if record is not None:  # nothing older waits: the queue was empty
                            return record
                finally:
                    self._reading.release()
            now = time.monotonic()
            if not data and self._closed is None and now >= deadline:
                raise TimeoutError(f"no data package from {self.where} within {asked} s")

    def _read_here(self, left: float) -> Any:
        """One read of the socket in the caller's thread (holding `_reading`), up to about `left` s:
        the record when the read was exactly one data package; else its events are handled."""
        sock = self._sock
        if sock is None:
            raise UsageError(NOT_CONNECTED, subject=self.where)
        try:
            if not ((self._sliced and left >= SLICE) or self._readable(sock, max(0.0, left))):
                return None
            chunk = sock.recv(self._bufsize)  # sliced: one call, SO_RCVTIMEO bounds it
        except BlockingIOError:
            return None  # no data within SLICE
        except OSError as exc:
            self._finish(self._ended(f"connection lost: {exc.strerror or exc}"))
            return None
        record = self.core.one_record(chunk)
        if record is not None:
            self.received += 1
            return record
        self._other_read(chunk)
        return None

    def _readable(self, sock: socket.socket, seconds: float) -> bool:
        """Whether the socket has something to read within `seconds` (poll, or select without it)."""
        if not hasattr(select, "poll"):
            return bool(select.select([sock], [], [], seconds)[0])
        poll = self._poll
        if poll is None:
            poll = self._poll = select.poll()
            poll.register(sock, select.POLLIN)
        return bool(poll.poll(seconds * 1000.0))

    def __iter__(self) -> Iterator[Any]:
        """Records until the connection closes cleanly: `receive()` called by a C iterator.

        Each step is one plain call of `receive` (its fast path: the lease renewed, the lock
        taken without waiting, one `recv`, the read's size and leading bytes compared, one
        `unpack`), not the resumption of a generator: at 500 Hz every step runs on cold caches,
        and a generator's frame cost ~6 µs of CPU more per package here. A clean end of the
        connection ends the iteration; a package that does not decode, a protocol fault or
        a time-out raises, as from `receive`.
        """
        return iter(self._next_or_end, _END)

    def _next_or_end(self) -> Any:
        try:
            return self.receive()
        except RtdeConnectionError:
            return _END

    def on_data(self, callback: Callable[[Any], None]) -> None:
        """Call `callback(record)` in the reader thread for every data package (keep it short).

        Push or pull: with a callback, records go to it instead of the queue (a queue
        nobody reads would only fill and count its oldest as skipped).
        """
        self._callbacks.append(callback)
        self.core.want_records = True

    def on_raw(self, callback: Callable[[bytes], None]) -> None:
        """Call `callback(package bytes)` for every data package: for recorders that batch
        (instead of the queue, as `on_data`). With no `on_data` callback, no records are made."""
        self._raw_callbacks.append(callback)
        self.core.want_records = bool(self._callbacks)

    def on_batch(self, callback: Callable[[Any], None]) -> None:
        """Call `callback(array)` in the reader thread with the data packages of each read as one
        numpy structured array (a row per package, fields by name as `RecipeCodec.dtype` has
        them: big-endian, vectors as (n,) sub-arrays; read-only, a view of the read's bytes).

        With `RtdeClient(batch=N)` a read holds about N packages: one wake-up, one `recv` and
        one array per N packages, and no Python object per package or value, for loggers and
        plots at 500 Hz. With no `on_data` callback, no records are made. Callbacks of a read run
        in the order `on_raw`, `on_batch`, `on_data`, each kind in the order added. Needs numpy.
        """
        require("numpy", "numpy", "on_batch")
        self._batch_callbacks.append(callback)
        self.core.want_records = bool(self._callbacks)

    # --- internals ----------------------------------------------------------

    def _write(self, data: bytes) -> None:
        if self._sock is None:
            raise RtdeConnectionError("not connected", subject=self.where)
        if self._closed is not None:  # the kernel would take the bytes of a closed connection
            raise self._closed
        if self._closing:
            raise RtdeConnectionError("closed by this client", subject=self.where)
        try:
            with self._send_lock:
                self._sock.sendall(data)
        except OSError as exc:
            raise RtdeConnectionError(f"connection lost while sending: {exc}", subject=self.where) from None

    def _request(self, data: bytes) -> Reply:
        """Send a request (built by the core just before) and wait for the reply matched to it."""
        request = self.core.last_request
        assert request is not None
        if self._closed is not None:
            self.core.forget(request)
            raise self._closed
        if self._low_mark > 1:
            self._wake_after(self._sock, 1)  # the reply must not wait for a batch
        self._lease = 0.0  # the reader thread reads the reply (the caller waits for it, not records)
        self._nudge.set()
        self._write(data)
        deadline = time.monotonic() + self.timeout
        while True:
            try:
                reply = self._replies.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                if self._closed is not None:
                    raise self._closed from None
                raise self.core.no_reply(request, self.timeout, self.where) from None
            if isinstance(reply, BaseException) or reply.request is request:
                return self._checked_reply(reply)
            # else the late reply of a request that timed out before: not this one's


def _recv_timeout(sock: socket.socket, seconds: float) -> bool:
    """Make a blocking recv return (EAGAIN) after `seconds` without data; False where the
    option is not a `struct timeval` as here (Windows takes milliseconds): reads then poll first."""
    if not sys.platform.startswith(("linux", "darwin", "freebsd")):
        return False
    try:
        sec = int(seconds)
        sock.setsockopt(
            socket.SOL_SOCKET, socket.SO_RCVTIMEO, struct.pack("@ll", sec, int((seconds - sec) * 1e6))
        )
    except (OSError, AttributeError, struct.error):
        return False
    return True


__all__ = ["InputRecipe", "RtdeClient", "RtdeConnectionError"]
