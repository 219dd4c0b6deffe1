"""The reader thread of the blocking RTDE client, and what every reader of its socket shares.

From `connect()` the thread drains the socket whenever the caller is not reading it
itself (the caller's lease, `LEASE`): a read of one data package goes to the `on_data`
callbacks as one record, several as a stream made in C, anything else through the
sans-I/O core's events (replies to the waiting caller, text messages to the log).
Kept apart from `client.py`, which holds the connection, the requests and the caller's reads.
"""

from __future__ import annotations

import collections
import logging
import queue
import select
import threading
import time
from collections.abc import Callable, Iterable
from functools import partial
from typing import Any

from rtde_spec.errors import RtdeConnectionError, RtdeSpecError
from rtde_spec.printable import safe_text
from rtde_spec.recipes.codec import PAYLOAD_OFFSET
from rtde_spec.rtde.client_base import ClientBase
from rtde_spec.rtde.client_protocol import DataRun, Reply, Text

log = logging.getLogger("rtde_spec.client")
LOG_LEVELS = (logging.CRITICAL, logging.ERROR, logging.WARNING, logging.INFO)  # by text-message level
# runs an iterator to its end, keeping nothing
_exhaust: Callable[[Iterable[Any]], None] = collections.deque(maxlen=0).extend
_new_tuple: Callable[..., Any] = tuple.__new__  # a record from its values: record types are tuples


def arrays_of(runs: list[DataRun], codec: Any) -> Any:
    """Runs of data packages that came one after another in a read (a protocol-1 controller's
    packages without their id are a run each) as one numpy array of the recipe's dtype, over
    bytes nothing else changes (a view of other bytes is copied: the array depends on no buffer)."""
    import numpy

    raw = runs[0].raw if len(runs) == 1 else b"".join(run.raw for run in runs)
    return numpy.frombuffer(raw if type(raw) is bytes else bytes(raw), codec.dtype)


class ThreadReads(ClientBase):
    """The reader thread's loop and the handing over of what any read brought (`RtdeClient` sets
    these attributes up in its `__init__`)."""

    _sock: Any
    _replies: queue.Queue[Reply | BaseException]
    _callbacks: list[Callable[[Any], None]]
    _raw_callbacks: list[Callable[[bytes], None]]
    _batch_callbacks: list[Callable[[Any], None]]
    _reading: threading.Lock
    _lease: float
    _nudge: threading.Event
    _closing: bool

    def _other_read(self, chunk: bytes) -> bool:
        """A read that is not one data package (held by the thread that holds `_reading`): its
        events handed over, or the end of the connection; True when it ended it."""
        if not chunk:
            self._finish(self._ended("the controller closed the connection"))
            return True
        try:
            self._handle(chunk)
        except Exception as exc:  # a faulty package ends the connection, as in the reader thread
            self._finish(exc)
            return True
        return False

    def _read_loop(self) -> None:
        """The reader thread: drains the socket whenever the caller is not reading it. A read of
        one data package goes to the `on_data` callbacks as one record, a read of several as a
        stream of records made one at a time (the newest values stay in the cache; nothing
        builds a list of them); anything else through the events (`_handle`)."""
        sock = self._sock
        assert sock is not None
        recv, reading, nudge, monotonic = sock.recv, self._reading, self._nudge, time.monotonic
        callbacks, raws = self._callbacks, self._raw_callbacks  # lists: callbacks added later count
        batches = self._batch_callbacks
        poller = select.poll() if hasattr(select, "poll") else None
        if poller is not None:
            poller.register(sock, select.POLLIN)
        try:
            while self._closed is None:
                lease = self._lease
                if lease and not self._closing:
                    left = lease - monotonic()
                    if left > 0:  # the caller reads the socket: keep off till it stops
                        nudge.wait(left)
                        nudge.clear()
                        continue
                reading.acquire()
                try:
                    lease = self._lease  # 0.0 while no caller ever read: no clock read per package
                    if self._closed is not None or (lease and lease > monotonic() and not self._closing):
                        continue
                    try:
                        if self._low_mark > 1 and poller is not None:
                            # a blocked recv keeps the low mark it started with; poll sees it lowered
                            poller.poll()
                        chunk = recv(self._bufsize)
                    except BlockingIOError:
                        continue  # SLICE without data
                    except OSError as exc:
                        self._finish(self._ended(f"connection lost: {exc.strerror or exc}"))
                        return
                    path = self.core.output_path if callbacks or raws or batches else None
                    if path is None or not chunk or len(chunk) % path.size:
                        self._other_read(chunk)
                        continue
                    if len(chunk) == path.size and chunk.startswith(path.lead) and self.core.aligned:
                        self.core.taken += path.size  # framed here: one package, nothing held before it
                        count = 1
                    else:
                        count = path.take(chunk, path.size, path.lead)
                    if not count:
                        self._other_read(chunk)
                        continue
                    self.received += count
                    for raw in raws:  # raw, then batch, then record callbacks, as `_deliver`
                        if count == 1:
                            raw(chunk)
                        else:
                            _exhaust(map(raw, DataRun([], chunk, path.size).packages()))
                    if batches:
                        self._arrays([DataRun([], chunk, path.size)])
                    if not callbacks:
                        continue
                    if count == 1:
                        record = _new_tuple(path.record_type, path.unpack(chunk, PAYLOAD_OFFSET))
                        for callback in callbacks:
                            callback(record)
                    elif len(callbacks) == 1:  # the loop in C, one record alive at a time
                        made = partial(_new_tuple, path.record_type)
                        _exhaust(map(callbacks[0], map(made, path.many(chunk))))
                    else:
                        for record in map(partial(_new_tuple, path.record_type), path.many(chunk)):
                            for callback in callbacks:
                                callback(record)
                finally:
                    reading.release()
        except BaseException as exc:
            self._finish(exc)

    def _handle(self, chunk: bytes) -> None:
        """The events of one read, in order. A function of its own so that the read's records
        and bytes are freed when it returns, while still in the cache, not at the next read.
        A faulty package ends the connection after the packages before it are handed over."""
        failed: RtdeSpecError | None = None
        try:
            events = self.core.receive(chunk)
        except RtdeSpecError as exc:
            events, failed = self.core.before_error, exc
        data: list[DataRun] = []
        for event in events:
            if isinstance(event, DataRun):
                data.append(event)
                continue
            if data:  # keep the order of data and replies
                self._deliver(data)
                data = []
            if isinstance(event, Text):
                level = LOG_LEVELS[min(event.level, 3)]  # the controller's words, never its escapes
                log.log(level, "%s: %s", safe_text(str(event.source)), safe_text(str(event.message)))
            else:
                self._replies.put(event)
        if data:
            self._deliver(data)
        if failed is not None:
            raise failed

    def _deliver(self, runs: list[DataRun]) -> None:
        """Hand over the data packages of one read: to the callbacks if there are any, else
        to the queue (the oldest dropped and counted when full).

        The deque is safe between one producer and consumers without a lock; the records are
        in it before `_reading` is released, so a caller waiting for that lock finds them.
        """
        records = runs[0].records if len(runs) == 1 else [r for run in runs for r in run.records]
        self.received += runs[0].count if len(runs) == 1 else sum(run.count for run in runs)
        if self._callbacks or self._raw_callbacks or self._batch_callbacks:
            for raw in self._raw_callbacks:  # raw, then batch, then record callbacks
                for run in runs:
                    for package in run.packages():
                        raw(package)
            if self._batch_callbacks:
                self._arrays(runs)
            for callback in self._callbacks:
                _exhaust(map(callback, records))  # the loop in C: a batch of 50 is 50 calls, no steps
            return
        room = self._data.maxlen - len(self._data)  # type: ignore[operator]
        if len(records) > room:
            self.skipped += len(records) - room  # the oldest go; the socket keeps being drained
        self._data.extend(records)

    def _arrays(self, runs: list[DataRun]) -> None:
        """The runs of a read that came one after another as one numpy array to the `on_batch`
        callbacks (a reply or a text between them makes two calls of `_deliver`)."""
        array = arrays_of(runs, self.core.output)
        for callback in self._batch_callbacks:
            callback(array)

    def _ended(self, cause: str) -> BaseException:
        if self._closing:
            return RtdeConnectionError("closed by this client", subject=self.where)
        return self.core.closed(self.where, cause)

    def _finish(self, exc: BaseException) -> None:
        self._closed = exc
        self._replies.put(exc)

    def _gone(self) -> BaseException:
        return self._closed or RtdeConnectionError("connection closed", subject=self.where)
