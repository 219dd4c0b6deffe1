"""A capture read from a pipe (`tcpdump -w - | rtde-spec capture -`): the pipe is widened, so a
fast writer's capture comes in blocks of what waits in it rather than 64 kB reads of ~90
packages, each costing a block's set-up (5-7x the CPU of the same file before).

Real pipes (os.pipe, a subprocess's standard input); no stand-ins.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from rtde_spec.capture.reading import pcapfile, pipes
from tests.capture_files import Conversation, rtde_packages, rtde_setup, run_capture, write

fcntl = pytest.importorskip("fcntl")
WIDENS = hasattr(fcntl, "F_SETPIPE_SZ")  # Linux; elsewhere a pipe is read as it is


def _capture(path: Path, count: int, *, acks: bool = False) -> tuple[bytes, int]:
    """A pcap of one RTDE session (setup, then `count` data packages, each followed by the
    client's ACK when `acks`); returns its bytes and where its data records start."""
    conv = Conversation(("10.0.0.2", 51000), ("10.0.0.10", 30004))
    rtde_setup(conv)
    setup_frames = len(conv.frames)
    for package in rtde_packages(count):
        conv.send("server", package)
        if acks:
            conv.bare("client")
    data = write(path, [conv]).read_bytes()
    at = 24
    for _ in range(setup_frames):
        at += 16 + int.from_bytes(data[at + 8 : at + 12], "little")
    return data, at


@pytest.mark.skipif(not WIDENS, reason="a pipe's size is set by fcntl(F_SETPIPE_SZ), which Linux has")
def test_what_waits_in_a_pipe_is_read_as_one_block_not_in_64_kB_pieces(tmp_path: Path) -> None:
    """The setup arrives first; then the writer puts ~0.8 of the widened pipe's size in at
    once, which it could not do into a 64 kB pipe without a reader: those packages come out
    as one block. Before: the write waited for the reader, and they came ~90 a block."""
    r, w = os.pipe()
    f = os.fdopen(r, "rb")
    try:
        head, start = _capture(tmp_path / "setup.pcap", 0)
        one = len(_capture(tmp_path / "one.pcap", 1)[0]) - start  # a data package's record
        os.write(w, head)
        stats: dict[str, int] = {}
        got = pcapfile.blocks(f, "pipe", stats)
        assert next(got).upto == start  # the setup, as it came
        size = fcntl.fcntl(r, fcntl.F_GETPIPE_SZ)
        assert size >= min(1 << 20, pipes._system_limit()), f"the pipe is still {size} bytes"
        count = int(0.8 * size) // one
        data, start = _capture(tmp_path / "burst.pcap", count)
        burst = data[start:]
        assert len(burst) < size
        writer = threading.Thread(target=os.write, args=(w, burst), daemon=True)
        writer.start()
        writer.join(10.0)
        fits = not writer.is_alive()  # the whole burst went into the pipe, nobody reading
        os.close(w)
        w = -1
        rest = list(got)  # drains the pipe whichever way it went
        assert fits, "the burst did not fit in the pipe: it was not widened"
        assert [len(b.offsets) for b in rest] == [count], "the waiting packages were not one block"
        assert "truncated" not in stats
    finally:
        f.close()
        if w >= 0:
            os.close(w)


def test_a_capture_piped_into_the_cli_gives_the_tables_of_the_same_file(tmp_path: Path) -> None:
    """Several MB with the peer's ACKs through the command's standard input (a pipe, widened
    where the system allows): the same tables, row for row, as the file read directly."""
    data, _ = _capture(tmp_path / "acked.pcap", 30_000, acks=True)
    assert len(data) > 3 << 20
    from_file = run_capture("acked.pcap", "-o", "file", "--format", "csv", cwd=tmp_path)
    assert from_file.returncode == 0, from_file.stderr
    piped = run_capture("-", "-o", "piped", "--format", "csv", cwd=tmp_path, stdin=data)
    assert piped.returncode == 0, piped.stderr

    def tables(folder: Path) -> dict[str, bytes]:  # each table's folder: its files are named for the input
        paths = (p for p in folder.rglob("*.csv") if not p.name.startswith("recipes-"))
        return {str(p.parent.relative_to(folder)): p.read_bytes() for p in paths}

    file, piped_tables = tables(tmp_path / "file"), tables(tmp_path / "piped")
    assert sorted(file) == sorted(piped_tables)
    outputs = [name for name in file if name.startswith("rtde_outputs")]
    assert outputs and sum(file[name].count(b"\n") for name in outputs) > 30_000  # header + rows
    assert file == piped_tables


def test_widen_leaves_what_is_no_pipe_alone(tmp_path: Path) -> None:
    """A regular file, or a stream without a descriptor, is not a pipe: nothing is asked of it."""
    import io

    path = tmp_path / "x.pcap"
    path.write_bytes(b"\0" * 100)
    with open(path, "rb") as f:
        assert pipes.widen(f, 1 << 20) == 0
    assert pipes.widen(io.BytesIO(b"x"), 1 << 20) == 0


@pytest.mark.skipif(not WIDENS, reason="a pipe's size is set by fcntl(F_SETPIPE_SZ), which Linux has")
def test_widen_never_shrinks_a_pipe() -> None:
    r, w = os.pipe()
    try:
        big = fcntl.fcntl(w, fcntl.F_SETPIPE_SZ, 1 << 20)
        with os.fdopen(os.dup(r), "rb") as f:
            assert pipes.widen(f, 1 << 16) == big
        assert fcntl.fcntl(r, fcntl.F_GETPIPE_SZ) == big
    finally:
        os.close(r)
        os.close(w)


def _with_terminal_stdin(args: list[str], typed: bytes = b"") -> subprocess.CompletedProcess[str]:
    """The CLI with a terminal (a pseudo-terminal) as standard input, `typed` typed into it."""
    main, side = os.openpty()
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", "rtde_spec", *args],
            stdin=side,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        os.close(side)
        side = -1
        if typed:
            os.write(main, typed)
        out, err = proc.communicate(timeout=60)
        return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
    finally:
        os.close(main)
        if side >= 0:
            os.close(side)


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="a pseudo-terminal is POSIX")
def test_capture_of_standard_input_that_is_a_terminal_is_refused_not_waited_on(tmp_path: Path) -> None:
    """`rtde-spec capture -` typed without a pipe waited for ever; now a usage error says why."""
    done = _with_terminal_stdin(["capture", "-", "-o", str(tmp_path / "out")])
    assert done.returncode == 2, done.stderr
    assert "standard input is a terminal" in done.stderr and "tcpdump -w -" in done.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="a pseudo-terminal is POSIX")
def test_decode_from_a_terminal_says_it_reads_hex_until_ctrl_d() -> None:
    from rtde_spec import build

    package = build("request_protocol_version_reply", accepted=True).hex()  # as the controller sends it
    done = _with_terminal_stdin(["decode", "-"], typed=package.encode() + b"\n\x04")
    assert done.returncode == 0, done.stderr
    assert "end with Ctrl-D" in done.stderr
    assert "accepted" in done.stdout
