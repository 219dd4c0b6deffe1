"""Batches of a capture's tables prepared and written on worker threads, in the order given
(`capture --jobs N`): the decoding thread frames and decodes, a worker encodes and writes the
front batch as soon as it is prepared; the tables come out byte-identical to one thread's."""

from __future__ import annotations

import sys
import threading
from collections import deque
from collections.abc import Callable, Mapping
from typing import Any


def _parquet_prepare(columns: Mapping[str, Any]) -> Any:
    from rtde_spec.output.parquet import prepared_columns

    return prepared_columns(columns)


# formats whose writers take a batch prepared on another thread (`write_prepared`)
PREPARED: dict[str, Callable[[Mapping[str, Any]], Any]] = {"parquet": _parquet_prepare}
Key = tuple[str, str, str]
WriteItem = Callable[[Key, bool, Any], None]


class _Slot:
    """One item given to `OrderedWrites`: a batch (prepared in turn) or a row (ready as given)."""

    __slots__ = ("item", "key", "prepare", "ready")

    def __init__(self, key: Key, prepare: Callable[[Any], Any] | None, item: Any) -> None:
        self.key, self.prepare, self.item = key, prepare, item
        self.ready = prepare is None


# s a thread waits for the GIL before it asks for it (Python's default: 0.005): the writing worker
# takes the GIL back after each row group it encoded, and waited ~0.3 s of a 1 M-package capture
# for the decoding thread to give it up; with 1 ms ~0.2 s (bench_capture.py, asleep@worker)
SWITCH_INTERVAL = 0.001


class OrderedWrites:
    """Batches prepared and written on worker threads, in the order they were given.

    The decoding thread reads and frames: it hands each batch over and goes on. A
    worker writes the front batch as soon as it is prepared (one worker at a time, so
    the files are those of a run without workers, byte for byte) and otherwise prepares
    the next batch. Encoding one file's row groups in order is the one chain that cannot
    be split, so it runs whenever its next batch is ready, and the threads that run are
    no more than `--jobs`: the decoding thread prepares batches too (the newest: the
    oldest is the writing worker's next), but only while `depth` of them wait (the
    workers are behind), instead of waiting. Memory stays bounded by `depth`, and a
    slow disk slows the decoder rather than filling memory. An error on a worker stops
    the workers and is raised in the decoding thread. While the workers run, Python's
    switch interval is `SWITCH_INTERVAL` (then as it was).
    """

    def __init__(self, workers: int, write: WriteItem, depth: int | None = None) -> None:

        self.write = write
        self.depth = depth if depth is not None else workers + 2
        self.queue: deque[_Slot] = deque()  # given and not yet written, in order
        self.todo: deque[_Slot] = deque()  # batches no thread has begun to prepare, in order
        self.writing = False  # a worker is writing the batch it took from the front
        self.stopped = False
        self.failed: BaseException | None = None
        self.cond = threading.Condition()
        self.threads = [
            threading.Thread(target=self._work, name=f"rtde-spec-write-{i}", daemon=True)
            for i in range(workers)
        ]
        self._interval = sys.getswitchinterval()
        sys.setswitchinterval(min(self._interval, SWITCH_INTERVAL))
        for thread in self.threads:
            thread.start()

    def add(self, key: Key, prepare: Callable[[Any], Any] | None, item: Any) -> None:
        """Hand over one item; while `depth` wait, prepare the newest batch no worker has begun."""
        slot = _Slot(key, prepare, item)
        with self.cond:
            self._check()
            self.queue.append(slot)
            if prepare is not None:
                self.todo.append(slot)
            self.cond.notify_all()
        self._help(lambda: len(self.queue) < self.depth)

    def finish(self) -> None:
        """Everything written (this thread helps prepare what is left); the threads end."""
        try:
            self._help(lambda: not self.queue and not self.writing)
        finally:
            self.drop()

    def drop(self) -> None:
        """Nothing more is written (an error, or abort): waiting batches are forgotten."""
        with self.cond:
            self.stopped = True
            self.queue.clear()
            self.todo.clear()
            self.cond.notify_all()
        for thread in self.threads:
            thread.join()
        if sys.getswitchinterval() == min(self._interval, SWITCH_INTERVAL):  # ours still: as it was
            sys.setswitchinterval(self._interval)

    def _help(self, done: Callable[[], bool]) -> None:
        """Until `done()`: prepare batches nobody has begun, else wait for the workers."""
        while True:
            with self.cond:
                self._check()
                if done() or self.stopped:  # stopped: nothing given is written any more
                    return
                if not self.todo:
                    self.cond.wait()
                    continue
                slot = self.todo.pop()  # the newest: the oldest is the writing worker's next
            self._prepare(slot)

    def _check(self) -> None:
        if self.failed is not None:
            raise self.failed

    def _prepare(self, slot: _Slot) -> None:
        try:
            prepared = slot.prepare(slot.item)  # type: ignore[misc]
        except BaseException as exc:
            self._fail(exc)
            raise
        with self.cond:
            slot.item, slot.ready = prepared, True
            self.cond.notify_all()

    def _fail(self, exc: BaseException) -> None:
        with self.cond:
            if self.failed is None:
                self.failed = exc
            self.cond.notify_all()

    def _work(self) -> None:
        """A worker: write the front batch when it is ready and nobody writes, else prepare one."""
        cond = self.cond
        while True:
            with cond:
                while True:
                    if self.stopped or self.failed is not None:
                        return
                    queue = self.queue
                    if not self.writing and queue and queue[0].ready:
                        slot, writes = queue.popleft(), True
                        self.writing = True
                        break
                    if self.todo:
                        slot, writes = self.todo.popleft(), False
                        break
                    cond.wait()
            if not writes:
                try:
                    self._prepare(slot)
                except BaseException:
                    return
                continue
            try:
                self.write(slot.key, slot.prepare is not None, slot.item)
            except BaseException as exc:
                self._fail(exc)
                return
            finally:
                with cond:
                    self.writing = False
                    cond.notify_all()
