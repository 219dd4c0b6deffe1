"""The guard against threads a test module leaves spinning (tests/spinning_threads.py)."""

from __future__ import annotations

import sys
import threading

import pytest

from .spinning_threads import ThreadWatch


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/task")
def test_a_thread_the_last_module_leaves_spinning_is_named_at_the_sessions_end() -> None:
    """No module follows the last one to look: the session's end watches its threads. A busy
    thread is named with the module that left it; an idle one is not."""
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            pass

    busy = threading.Thread(target=spin, name="busy-left-behind", daemon=True)
    idle = threading.Thread(target=stop.wait, name="idle-left-behind", daemon=True)
    watch = ThreadWatch()
    try:
        busy.start()
        idle.start()
        watch.spinning_after("tests.the_last_module")
        found = watch.spinning_at_the_end(look=1.0)  # a second: half a core even beside other load
    finally:
        stop.set()
        busy.join()
        idle.join()
    assert len(found) == 1, found
    assert "'busy-left-behind', alive since tests.the_last_module ended" in found[0]
    assert ThreadWatch().spinning_at_the_end(look=5.0) == []  # nothing seen: no wait, nothing named
