"""Issue 18.6: stdin claiming a huge package buffers only what arrives, and `decode -`
decodes as bytes come, so memory follows what has arrived, not the input's length.

The CLI runs as a real subprocess on the same rtde_spec the tests import, its peak
resident size (VmHWM) read from /proc at its exit; an address-space limit keeps a
regression from taking the machine down.
"""

from __future__ import annotations

import os
import resource
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import rtde_spec

ROOT = Path(rtde_spec.__file__).resolve().parents[1]
# the CLI, reporting its own peak resident size on stderr when it exits
CLI = """
import atexit, sys
def _hwm():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            sys.stderr.write("\\nVMHWM_KB %s\\n" % line.split()[1])
atexit.register(_hwm)
from rtde_spec.cli.main import main
sys.exit(main(sys.argv[1:]))
"""
LIMIT = 3 << 30  # address space of the child: a blow-up fails, the machine lives


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT, LIMIT))


def _spawn(*args: str) -> subprocess.Popen[bytes]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-c", CLI, *args],
        stdin=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        env=env,
        preexec_fn=_limit,
    )


def _peak_mb(stderr: bytes) -> float:
    line = next(x for x in stderr.decode().splitlines() if x.startswith("VMHWM_KB"))
    return int(line.split()[1]) / 1024


def test_a_claim_of_2_31_bytes_on_stdin_is_refused_as_it_arrives_without_waiting_for_the_end() -> None:
    """The header claims 2^31 bytes and the writer never closes: the claim is refused at
    once (offset 0, the size named), not after buffering the stream to its end."""
    proc = _spawn("decode", "-", "--protocol", "primary", "--format", "jsonl")
    assert proc.stdin is not None and proc.stderr is not None
    proc.stdin.write(struct.pack(">IB", 1 << 31, 16) + bytes(64 << 10))
    proc.stdin.flush()
    try:
        code = proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise AssertionError("decode - waited for the end of stdin instead of refusing the claim") from None
    finally:
        proc.stdin.close()
    err = proc.stderr.read().decode()
    assert code == 1, err
    assert "byte offset 0" in err and "2147483648" in err and "field size" in err


def test_decode_stdin_memory_follows_what_arrived_not_the_input_length() -> None:
    """192 MiB of 1 MiB primary messages through a pipe: the decoder's peak stays far
    below the input (it was read whole, then joined: > 2x the input)."""
    message = struct.pack(">IB", 1 << 20, 99) + bytes(
        (1 << 20) - 5
    )  # a type the spec does not know: kept raw
    count = 192
    proc = _spawn("decode", "-", "--protocol", "primary", "--format", "jsonl")
    assert proc.stdin is not None and proc.stderr is not None
    errors: list[bytes] = []
    reader = threading.Thread(target=lambda: errors.append(proc.stderr.read()), daemon=True)  # type: ignore[union-attr]
    reader.start()
    started = time.monotonic()
    try:
        for _ in range(count):
            proc.stdin.write(message)
    except BrokenPipeError:
        pass
    finally:
        proc.stdin.close()
    code = proc.wait(timeout=600)
    reader.join(timeout=60)
    elapsed = time.monotonic() - started
    err = errors[0] if errors else b""
    assert code == 0, err.decode()[-2000:]
    peak = _peak_mb(err)
    print(f"peak {peak:.0f} MB, {elapsed:.1f} s")
    assert peak < 160, f"peak {peak:.0f} MB for {count} MiB through stdin"
    assert elapsed < 300, f"{elapsed:.0f} s"
