"""A file written by a second thread, so encoding the next batch overlaps writing this one.

A write of a big block spends most of its time in the system call, with the GIL
released; handing it to a thread lets the decoder use the other core meanwhile.
Small writes are gathered into blocks of about `BLOCK` bytes first, so a stream of
single rows costs no thread hand-off per row. At most `depth` blocks wait, so
memory stays bounded; an error in the writing thread is raised in the caller's
thread at its next write, flush or close.
"""

from __future__ import annotations

import io
import queue
import threading
from typing import IO

_STOP = None
BLOCK = 1 << 20


class BackgroundStream(io.RawIOBase):
    """Wraps a binary stream; write() queues the block, a daemon thread writes it."""

    def __init__(self, stream: IO[bytes], depth: int = 2) -> None:
        super().__init__()
        self.raw = stream
        self._queue: queue.Queue[bytes | None] = queue.Queue(maxsize=depth)
        self._error: BaseException | None = None  # raised once, in the caller's thread
        self.failed: BaseException | None = None  # kept: the file has a hole, its writer drops it
        self._small = bytearray()
        self._thread = threading.Thread(target=self._run, name="rtde-spec-writer", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            block = self._queue.get()
            try:
                if block is _STOP:
                    return
                if self.failed is None:  # after a failure, drain without writing
                    self.raw.write(block)
            except BaseException as exc:  # handed to the caller's thread
                self._error = self.failed = exc
            finally:
                self._queue.task_done()

    def _check(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def writable(self) -> bool:
        return True

    def write(self, block: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        self._check()
        size = len(block)
        if size >= BLOCK and not self._small:
            self._queue.put(bytes(block))  # no copy for bytes; a copy of anything mutable
        else:
            self._small += block
            if len(self._small) >= BLOCK:
                self._hand_over()
        return size

    def _hand_over(self) -> None:
        if self._small:
            self._queue.put(bytes(self._small))
            self._small.clear()

    def flush(self) -> None:
        """Wait until every queued block is written, then flush the stream below."""
        if self.closed or not self._thread.is_alive():  # closed, or its thread stopped: nothing queued
            return
        self._hand_over()
        self._queue.join()
        self._check()
        self.raw.flush()

    def close_quietly(self) -> None:
        """Stop the thread after an error elsewhere: queued blocks are dropped, nothing is raised."""
        if self._thread.is_alive():
            self.failed = self.failed or OSError("output abandoned")  # the thread drains without writing
            self._small.clear()
            self._queue.put(_STOP)
            self._thread.join()
        self._error = None
        if not self.closed:
            super().close()

    def close(self) -> None:
        """Write what is queued, stop the thread; the stream below stays open (its owner closes it)."""
        if self._thread.is_alive():
            self._hand_over()
            self._queue.put(_STOP)
            self._thread.join()
        self._check()
        self.raw.flush()
        super().close()
