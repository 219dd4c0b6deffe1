"""`capture --jobs N` over several files: one worker process per core, stopped cleanly.

A worker stopped by a signal must not leave half-written tables or hidden temp files, and
must not outlive the command. So the parent forwards Ctrl-C and SIGTERM to its workers
(they get none when the signal went to the parent alone); a worker reading a capture stops
as the one-process path does (the file's tables dropped, its earlier ones kept) and returns
what it has, an idle one exits; pending files are cancelled, not started; and a worker
whose parent died (SIGKILL) gets SIGTERM from the kernel (Linux) instead of waiting on a
queue forever. That signal is one of its own, not SIGTERM: the kernel sends it when the
thread that started the worker ends, and a killed command's main thread may end before its
other threads, so the worker's parent still looks alive (`getppid` names the same process).
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Sequence
from concurrent.futures import wait as wait_for
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from types import FrameType

    from rtde_spec.capture.decoder import CaptureInterrupted, CapturePath
    from rtde_spec.capture.tables.summary import CaptureSummary

_busy = False  # a worker is decoding a file: a signal stops the file, else it ends the worker
_stopping = False  # that file is being stopped: later signals change nothing
_halted = False  # the command is stopping: a file handed to this worker after that is not started
_parent = 0  # the pid of the command that started this worker
_orphaned = False  # the command is gone (or going): nobody will place what this worker prepared
_unplaced: list[Path] = []  # temp files of tables this worker prepared, for its parent to place
_STOPS = ("SIGINT", "SIGTERM", "SIGHUP")
STOP_GRACE = 20.0  # s a stopped worker has to drop its file and end before it is ended


def decode_in_workers(
    files: Sequence[CapturePath], jobs: int, target: tuple[Any, ...], kw: dict[str, Any]
) -> tuple[list[CaptureSummary], list[CaptureInterrupted] | None]:
    """Each file decoded by `decode_prepared(file, *target, **kw)` in a worker, its tables put
    in place here, in input order: a table's name is given to its recipe as `--jobs 1` gives
    it, whichever worker finishes first (`capture/tables/names.py`). A file whose names an
    earlier file took (both met new recipes) is decoded again here, under the right ones.

    Returns the summaries of the files finished and, after an interrupt, the stops of the
    files cut short (None when nothing was interrupted).
    """
    import ctypes  # noqa: F401  # here: a worker short of descriptors could not import it (_end_with_parent)
    from concurrent.futures import ProcessPoolExecutor

    from rtde_spec.capture.decoder import decode_to_directory, place

    pool = ProcessPoolExecutor(max_workers=jobs, initializer=_start_worker)
    futures: list[Any] = []
    summaries: list[CaptureSummary] = []
    try:
        # submitting starts the workers: out of descriptors, the second may fail after the first
        # started, which must not be left waiting for work once this command has ended
        futures += [pool.submit(_decode_one, f, target, kw) for f in files]
        for path, future in zip(files, futures, strict=True):
            got = future.result()
            if not isinstance(got, tuple):  # interrupted in the worker (a signal to it alone)
                raise KeyboardInterrupt
            summary, prepared = got
            if not place(prepared, path, summary):
                summary = decode_to_directory(path, *target, **kw)
            summaries.append(summary)
    except KeyboardInterrupt:
        return _stop(pool, futures, summaries)
    except BaseException:
        if len(futures) < len(files):  # the pool did not start: its workers are ended here
            workers = _workers_of(pool)
            pool.shutdown(wait=False, cancel_futures=True)
            for worker in workers:
                worker.terminate()
            _end(workers)
        else:
            pool.shutdown(wait=True, cancel_futures=True)
        _discard_unplaced(futures[len(summaries) :])
        raise
    pool.shutdown(wait=True)
    return summaries, None


def _discard_unplaced(futures: list[Any]) -> None:
    """Files decoded but not put in place (an earlier one failed or was stopped): their temp files go."""
    for future in futures:
        if future.done() and not future.cancelled() and future.exception() is None:
            got = future.result()
            if isinstance(got, tuple):
                got[1].discard()


def _stop(
    pool: Any, futures: list[Any], placed: list[CaptureSummary]
) -> tuple[list[CaptureSummary], list[CaptureInterrupted]]:
    """Stop every worker between or inside files; the files put in place are finished, every
    other one is not (its tables dropped, those of an earlier run kept)."""
    from rtde_spec.capture.decoder import CaptureInterrupted
    from rtde_spec.capture.tables.signals import signals_held

    for future in futures:
        future.cancel()  # not started: never started
    workers = _workers_of(pool)
    for worker in workers:
        try:
            os.kill(worker.pid, signal.SIGINT)  # a signal sent to the parent alone reaches them too
        except OSError:
            pass
    pool.shutdown(wait=False, cancel_futures=True)
    _end(workers)
    wait_for(futures, timeout=STOP_GRACE)  # each settled once its worker has ended
    stops: list[CaptureInterrupted] = []
    for future in futures[len(placed) :]:
        if future.cancelled() or not future.done() or future.exception() is not None:
            continue
        got = future.result()
        if isinstance(got, CaptureInterrupted):
            stops.append(got)
        else:  # decoded, waiting for an earlier file to be placed first: dropped with the stop
            summary, prepared = got
            with signals_held(replay=False):
                prepared.discard()
            stops.append(CaptureInterrupted(summary, kept=False))
    return placed, stops


def _workers_of(pool: Any) -> list[Any]:
    """The pool's worker processes (its own record of them: the pool offers no other)."""
    return list((getattr(pool, "_processes", None) or {}).values())


def _end(workers: list[Any]) -> None:
    """Wait for the workers to end, STOP_GRACE at most, then end them. Not the pool's own wait:
    once a worker has died (a pool CPython calls broken), Python 3.11's pool waits for the others
    by offering each a stop on a full queue, in a loop that never ends while one lives (a
    command seen spinning 40 minutes after its stop); with no worker left the loop ends."""
    deadline = time.monotonic() + STOP_GRACE
    for worker in workers:
        worker.join(max(0.0, deadline - time.monotonic()))
    for worker in workers:
        if worker.is_alive():
            worker.terminate()  # SIGTERM: the file it decodes is dropped, the old tables stay
            worker.join(2.0)
        if worker.is_alive():
            worker.kill()
            worker.join(2.0)


def _start_worker() -> None:
    """In each worker: Parquet in its own thread, signals handled, ended with its parent."""
    from rtde_spec.output.parquet import one_core_per_process

    one_core_per_process()
    for name in _STOPS:
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), _on_signal)
    _end_with_parent()


def _on_parent_death(signum: int, frame: FrameType | None) -> None:
    """The kernel's word that the command is dying: stop as for SIGTERM, and remove what it
    would have placed."""
    global _orphaned
    _orphaned = True
    _on_signal(int(signal.SIGTERM), frame)


def _on_signal(signum: int, frame: FrameType | None) -> None:
    global _stopping, _halted
    _halted = True
    if _busy:
        if _stopping:  # the same stop again (to the group, and forwarded by the parent)
            return
        _stopping = True
        raise KeyboardInterrupt  # decode_prepared drops the file's tables, keeps the old ones
    if signum == signal.SIGINT and not _gone():
        # idle, or sending a finished file's result to the parent: ending here could cut that
        # message short, and the pool's reader would wait for its rest for ever (a command that
        # never ends). The parent stops the pool, which ends an idle worker cleanly.
        return
    _exit(128 + signum)  # idle, and the parent is gone or wants us gone: nothing of ours is open


def _end_with_parent() -> None:
    """A signal from the kernel when the parent process dies (Linux's PR_SET_PDEATHSIG)."""
    global _parent
    parent = _parent = os.getppid()
    if not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        death = signal.SIGRTMIN + 2  # SIGRTMIN itself may be taken by the C library's threads
        signal.signal(death, _on_parent_death)
        ctypes.CDLL(None, use_errno=True).prctl(1, int(death))  # 1: PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # no signal then: a thread looks for the parent instead
        threading.Thread(target=_watch_parent, args=(parent,), name="rtde-spec-parent", daemon=True).start()
        return
    if os.getppid() != parent:  # it died before the request took effect
        os._exit(128 + int(signal.SIGTERM))


def _watch_parent(parent: int) -> None:
    """End this worker once its parent is gone (where the kernel will not signal it)."""
    while os.getppid() == parent:
        time.sleep(0.5)
    _exit(128 + int(signal.SIGTERM))


def _decode_one(path: CapturePath, target: tuple[Any, ...], kw: dict[str, Any]) -> Any:
    """One file in a worker: its summary and its tables prepared for the parent to place, or
    the CaptureInterrupted that stopped it."""
    global _busy, _stopping
    from rtde_spec.capture.decoder import CaptureInterrupted, decode_prepared, directory_sink
    from rtde_spec.capture.tables.summary import CaptureSummary

    outdir, fmt, recipe = target
    if _halted:  # queued before the stop (the pool hands on one more than it has workers)
        return CaptureInterrupted(CaptureSummary(str(path)), kept=False)
    _busy, _stopping = True, False
    sink = None
    try:
        sink = directory_sink(path, outdir, fmt)
        summary, prepared = decode_prepared(path, sink, recipe, **kw)
        _unplaced.extend(part.temp for part in prepared.parts)
        return summary, prepared
    except CaptureInterrupted as stop:
        return stop
    except KeyboardInterrupt:  # the stop came after the file was decoded: it is dropped all the same
        if sink is not None:
            sink.abort()
        return CaptureInterrupted(CaptureSummary(str(path)), kept=False)
    finally:
        _busy = False
        if _gone():  # the parent died (its signal stopped this file): no one takes the
            _exit(128 + int(signal.SIGTERM))  # result or sends more work


def _gone() -> bool:
    """The command that started this worker is dead or dying."""
    return _orphaned or os.getppid() != _parent


def _exit(code: int) -> None:
    """End the worker; the temp files of tables it prepared that the parent did not place go
    first (the parent died: nobody will place or drop them)."""
    if _gone():
        for temp in _unplaced:
            try:
                temp.unlink()
            except OSError:  # placed (renamed) or dropped already
                pass
    os._exit(code)
