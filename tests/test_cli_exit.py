"""How the `rtde-spec` command ends (`cli.main.entry`): after `main()` the process leaves without
Python's teardown of every module and object, which the operating system frees at once, but
only once nothing else runs, and with everything printed.

An `atexit` handler in the child stands for the teardown: it runs at a normal interpreter exit
and not at the fast one. Each command runs as a user runs it, in its own interpreter.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.capture_files import rtde_capture, rtde_packages

ENTRY = """
import atexit, sys, threading, time
atexit.register(lambda: print("teardown", file=sys.stderr, flush=True))
if sys.argv[1] == "thread":  # a thread of the caller's still running when main() returns
    threading.Thread(target=time.sleep, args=(3.0,)).start()  # alive when main() returns, even under load
sys.argv = ["rtde-spec", *sys.argv[2:]]
from rtde_spec.cli.main import entry
entry()
"""


def run_entry(*args: str, thread: bool = False, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", ENTRY, "thread" if thread else "-", *args],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=cwd,
    )


def test_a_capture_ends_without_teardown_with_its_tables_and_summary_whole(tmp_path: Path) -> None:
    pcap = rtde_capture(tmp_path / "s.pcap", rtde_packages(500))
    done = run_entry("capture", str(pcap), "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert "teardown" not in done.stderr  # the interpreter was not torn down object by object
    assert "summary" in done.stderr and "tables: rtde_outputs_1 (" in done.stdout  # all printed
    import pyarrow.parquet as pq

    (table,) = (tmp_path / "out").rglob("rtde_outputs_1/**/*.parquet")
    assert pq.read_table(table).num_rows == 500


def test_stdout_to_a_file_holds_every_line_the_command_printed(tmp_path: Path) -> None:
    listing = tmp_path / "fields.txt"
    with listing.open("w") as out:
        done = subprocess.run(
            [sys.executable, "-c", ENTRY, "-", "fields", "--direction", "output"],
            stdout=out,
            stderr=subprocess.PIPE,
            text=True,
            timeout=300,
        )
    assert done.returncode == 0 and "teardown" not in done.stderr, done.stderr
    from rtde_spec import Catalogue

    outputs = [f.name for f in Catalogue.builtin().fields("output")]
    text = listing.read_text()
    assert all(f"\n{name} " in text for name in outputs)  # the last lines too: flushed before the end


def test_an_error_keeps_its_exit_code_and_message() -> None:
    done = run_entry("capture", "/nonexistent/no.pcap", "-o", "/nonexistent/out")
    assert done.returncode == 2
    assert "error: file /nonexistent/no.pcap: no such file" in done.stderr
    assert "teardown" not in done.stderr


def test_a_thread_still_running_gets_the_usual_exit_and_is_waited_for() -> None:
    done = run_entry("fields", "--direction", "output", thread=True)
    assert done.returncode == 0
    assert "teardown" in done.stderr  # Python's own exit: it joined the thread, then tore down


def test_a_reader_that_closes_the_pipe_early_is_not_an_error() -> None:
    """`rtde-spec fields | head -1`: the reader takes a line and goes."""
    proc = subprocess.Popen(
        [sys.executable, "-c", ENTRY, "-", "fields"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stdout is not None and proc.stderr is not None
    assert proc.stdout.readline().startswith("name")
    proc.stdout.close()
    err = proc.stderr.read()
    assert proc.wait(300) == 0, err
    assert "Exception ignored" not in err and "BrokenPipeError" not in err, err
