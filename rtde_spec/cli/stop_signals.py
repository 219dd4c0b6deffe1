"""SIGTERM and SIGHUP stop a command as Ctrl-C does, once; SIGINT stops it even where the
shell started it ignoring Ctrl-C (a script's background job).

A service manager, `docker stop` or a closed terminal sends them; scripts and supervisors
often send them twice (to the process and to its group). The first one stops the command,
so its cleanup runs (temp files removed, workers stopped, old outputs kept); the ones that
come while it stops are ignored, so they cannot cut that cleanup short. A command that takes
the signals itself (`serve`: as callbacks of its event loop) says so with `stopping()`.
"""

from __future__ import annotations

import signal
from typing import Any

SIGNALS = ("SIGTERM", "SIGHUP")
_STATE = {"stopping": False}


def interrupt(signum: int, frame: object) -> None:
    """The handler: KeyboardInterrupt for the first stop signal, nothing for the later ones."""
    if _STATE["stopping"]:
        return
    _STATE["stopping"] = True
    raise KeyboardInterrupt


def stopping() -> None:
    """A stop has begun (a command that handles the signal itself): later ones are ignored."""
    _STATE["stopping"] = True


def stop_on_terminate() -> dict[int, Any]:
    """`interrupt` for SIGTERM and SIGHUP where they have their default action (nohup's ignored
    SIGHUP stays ignored), Python's Ctrl-C for a SIGINT the shell ignored; returns the handlers
    replaced, for `restore`. Left as they are when not called from the main thread
    (`main()` run in a thread of a program) or where the system has no such signal."""
    _STATE["stopping"] = False
    previous: dict[int, Any] = {}
    for name in SIGNALS:
        signum = getattr(signal, name, None)
        if signum is None:
            continue
        try:
            if signal.getsignal(signum) is signal.SIG_DFL:
                previous[signum] = signal.signal(signum, interrupt)
        except ValueError:  # not the main thread
            return previous
    interrupt_ignored = getattr(signal, "SIGINT", None)
    if interrupt_ignored is not None and signal.getsignal(interrupt_ignored) is signal.SIG_IGN:
        # a script's background job (`rtde-spec record ... &`: the shell has it ignore Ctrl-C):
        # `kill -INT` stops it as Ctrl-C does, as it stops tcpdump (it was ignored: the script
        # waited for ever)
        previous[interrupt_ignored] = signal.signal(interrupt_ignored, signal.default_int_handler)
    return previous


def restore(previous: dict[int, Any]) -> None:
    for signum, handler in previous.items():
        signal.signal(signum, handler)
