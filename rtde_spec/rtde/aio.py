"""The asyncio RTDE client: the same sans-I/O core as the blocking one, on asyncio streams.

    async with AsyncRtdeClient(host) as client:
        await client.setup_outputs(["timestamp", "actual_q"], 125)
        await client.start()
        async for record in client: ...

A reader task drains the socket from connect on; data packages wait in a bounded
queue (oldest dropped, counted in `skipped`); every await has a timeout. As with the
blocking client, a clean close ends `async for` quietly, while a package that does not
decode, breaks the protocol or is cut off by the close ends it with that error.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator, Callable, Sequence
from typing import Any

from rtde_spec._generated.constants import RTDE_PORT
from rtde_spec.errors import ProtocolError, RtdeConnectionError, RtdeSpecError, UsageError, require
from rtde_spec.rtde.client_base import NOT_CONNECTED, ClientBase
from rtde_spec.rtde.client_protocol import DataRun, InputRecipe, Reply, Text
from rtde_spec.rtde.client_thread import LOG_LEVELS, arrays_of

log = logging.getLogger("rtde_spec.client")


def _wake(waiter: asyncio.Future[None]) -> None:
    if not waiter.done():
        waiter.set_result(None)


class AsyncRtdeClient(ClientBase):
    def __init__(self, host: str, port: int = RTDE_PORT, **options: Any) -> None:
        super().__init__(host, port, **options)
        self._waiter: asyncio.Future[None] | None = None  # set when records (or the end) come
        self._replies: asyncio.Queue[Reply | BaseException] = asyncio.Queue()
        self._writer: asyncio.StreamWriter | None = None
        self._task: asyncio.Task[None] | None = None
        self._batch_callbacks: list[Callable[[Any], None]] = []

    async def connect(self, protocol_version: int | None = None) -> AsyncRtdeClient:
        if self._writer is not None:
            state = "was closed" if self._closed is not None else "is connected"
            raise UsageError(
                f"this client {state}; make a new AsyncRtdeClient to connect again", subject=self.where
            )
        try:
            reader, self._writer = await asyncio.wait_for(
                asyncio.open_connection(self.host, self.port), self.timeout
            )
        except (OSError, asyncio.TimeoutError) as exc:
            raise RtdeConnectionError(f"cannot connect to the RTDE port: {exc}", subject=self.where) from None
        self._task = asyncio.get_running_loop().create_task(self._read_loop(reader))
        try:
            for version in self._versions_to_try(protocol_version):
                if (await self._request(self.core.request_protocol_version(version))).message.accepted:  # type: ignore[attr-defined]
                    break
            else:
                raise ProtocolError("the controller accepted no protocol version", subject=self.where)
            await self._request(self.core.get_controller_version())
        except BaseException:  # no connection or reader task left behind
            await self.close()
            raise
        return self

    async def setup_outputs(self, names: Sequence[str] | str, frequency: float = 125.0) -> Any:
        await self._request(self.core.setup_outputs(names, frequency))
        return self.core.output

    async def setup_inputs(self, names: Sequence[str] | str) -> InputRecipe:
        await self._request(self.core.setup_inputs(names))
        return self.core.inputs[max(self.core.inputs)]

    async def start(self) -> None:
        if not (await self._request(self.core.start())).message.accepted:  # type: ignore[attr-defined]
            raise ProtocolError("the controller refused to start", subject=self.where)
        if self.batch > 1 and self.core.output is not None:
            self._wake_after(self._socket(), self.batch * self.core.output.package_size)

    def _socket(self) -> Any:
        return self._writer.get_extra_info("socket") if self._writer is not None else None

    async def pause(self) -> None:
        await self._request(self.core.pause())

    async def send(self, recipe: InputRecipe, values: Any = None, **named: Any) -> None:
        await self._write(self.core.send_inputs(recipe, values, named))

    def on_batch(self, callback: Callable[[Any], None]) -> None:
        """Call `callback(array)` in the event loop with the data packages of each read as one
        numpy structured array (as `RtdeClient.on_batch`: a read-only view of the read's bytes,
        a row per package); instead of records, which are then not made."""
        require("numpy", "numpy", "on_batch")
        self._batch_callbacks.append(callback)
        self.core.want_records = False

    async def receive(self, timeout: float | None = None) -> Any:
        """The next record; waits on one future with a timer (no task per wait, as wait_for makes)."""
        if self._batch_callbacks:
            raise UsageError(
                "data packages go to the on_batch callbacks, not to receive()", subject=self.where
            )
        data = self._data
        if data:
            return data.popleft()
        loop = asyncio.get_running_loop()
        wait = self.timeout if timeout is None else timeout  # 0: only what is there, no wait
        deadline = loop.time() + wait
        while not data:
            if self._closed is not None:
                raise self._closed
            if self._writer is None:
                raise UsageError(NOT_CONNECTED, subject=self.where)
            if loop.time() >= deadline:
                raise TimeoutError(f"no data package from {self.where} in time")
            waiter = self._waiter = loop.create_future()
            timer = loop.call_at(deadline, _wake, waiter)
            try:
                await waiter
            finally:
                timer.cancel()
                self._waiter = None
        return data.popleft()

    async def __aiter__(self) -> AsyncIterator[Any]:
        while True:
            try:
                yield await self.receive()
            except RtdeConnectionError:
                return

    async def close(self) -> None:
        if self._closed is None and self._writer is not None:  # what a later call raises
            self._closed = RtdeConnectionError("closed by this client", subject=self.where)
        if self._writer is not None:
            self._writer.close()
        if self._task is not None:
            self._task.cancel()
            try:
                await self._task
            except (asyncio.CancelledError, Exception):
                pass

    async def __aenter__(self) -> AsyncRtdeClient:
        return await self.connect() if self._writer is None else self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def _write(self, data: bytes) -> None:
        if self._writer is None:
            raise RtdeConnectionError("not connected", subject=self.where)
        if self._closed is not None:  # the transport would take the bytes of a closed connection
            raise self._closed
        try:
            self._writer.write(data)
            await self._writer.drain()
        except OSError as exc:
            raise RtdeConnectionError(f"connection lost while sending: {exc}", subject=self.where) from None

    async def _request(self, data: bytes) -> Reply:
        """Send a request (built by the core just before) and wait for the reply matched to it."""
        request = self.core.last_request
        assert request is not None
        if self._closed is not None:
            self.core.forget(request)
            raise self._closed
        if self._low_mark > 1:
            self._wake_after(self._socket(), 1)  # the reply must not wait for a batch
        await self._write(data)
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.timeout
        while True:
            try:
                reply = await asyncio.wait_for(self._replies.get(), max(0.0, deadline - loop.time()))
            except asyncio.TimeoutError:
                if self._closed is not None:
                    raise self._closed from None
                raise self.core.no_reply(request, self.timeout, self.where) from None
            if isinstance(reply, BaseException) or reply.request is request:
                return self._checked_reply(reply)
            # else the late reply of a request that timed out before: not this one's

    async def _read_loop(self, reader: asyncio.StreamReader) -> None:
        try:
            while True:
                try:
                    chunk = await reader.read(max(65536, 2 * self._low_mark))
                except OSError as exc:
                    raise self.core.closed(self.where, f"connection lost: {exc.strerror or exc}") from None
                if not chunk:
                    raise self.core.closed(self.where)
                failed: RtdeSpecError | None = None
                try:
                    events = self.core.receive(chunk)
                except RtdeSpecError as exc:  # the packages before the fault are kept
                    events, failed = self.core.before_error, exc
                runs: list[DataRun] = []  # for on_batch: runs one after another, one array
                for event in events:
                    if isinstance(event, DataRun) and self._batch_callbacks:
                        runs.append(event)
                        continue
                    runs = self._hand_arrays(runs)
                    if isinstance(event, DataRun):
                        got = len(event.records)
                        self.received += got
                        self.skipped += max(0, len(self._data) + got - self._data.maxlen)  # type: ignore[operator]
                        self._data.extend(event.records)
                        self._wake()
                    elif isinstance(event, Text):
                        log.log(LOG_LEVELS[min(event.level, 3)], "%s: %s", event.source, event.message)
                    else:
                        self._replies.put_nowait(event)
                self._hand_arrays(runs)
                if failed is not None:
                    raise failed
        except asyncio.CancelledError:
            raise
        except BaseException as exc:  # kept as raised: a protocol error is not a quiet close
            self._closed = exc
            self._replies.put_nowait(exc)
            self._wake()

    def _hand_arrays(self, runs: list[DataRun]) -> list[DataRun]:
        """Runs that came one after another as one array to the `on_batch` callbacks; [] after."""
        if runs:
            self.received += sum(run.count for run in runs)
            array = arrays_of(runs, self.core.output)
            for callback in self._batch_callbacks:
                callback(array)
        return []

    def _wake(self) -> None:
        """Wake the caller waiting in receive (if any)."""
        if self._waiter is not None:
            _wake(self._waiter)
