"""Issue 18.6: a primary LIST or MATRIX count is checked against the bytes left before
anything is built, and decoded values cost a small multiple of their bytes.

Each decode runs in a child process under an address-space limit and a time-out, so
a regression fails the test instead of exhausting the machine; the child measures
its allocations with tracemalloc and prints them as JSON.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

import rtde_spec

ROOT = Path(rtde_spec.__file__).resolve().parents[1]
LIMIT = 2 << 30

# builds a Program State global variables update message of the given value bytes,
# decodes it, prints {"error": ..., "peak": bytes, "size": bytes}
CHILD = r"""
import json, struct, sys, time, tracemalloc
from rtde_spec.errors import DecodeError
from rtde_spec.primary.codec import decode_message, default_codec

values = bytes.fromhex(sys.stdin.read())
body = struct.pack(">QBH", 0, 1, 0) + values  # timestamp, global_variables_update_message, start_index
message = struct.pack(">IB", 5 + len(body), 25) + body
default_codec()  # the codec is built once per process: not the message's cost
tracemalloc.start()
started = time.perf_counter()
out = {"size": len(message)}
try:
    decoded = decode_message(message)
    out["count"] = len(decoded.variable_values)
except DecodeError as exc:
    out.update(error=str(exc), field=exc.field, offset=exc.offset, expected=exc.expected, actual=exc.actual)
out["peak"] = tracemalloc.get_traced_memory()[1]
out["seconds"] = time.perf_counter() - started
print(json.dumps(out))
"""


def _limit() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (LIMIT, LIMIT))


def decode_in_child(values: bytes, timeout: float = 120) -> dict[str, object]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    try:
        result = subprocess.run(
            [sys.executable, "-c", CHILD],
            input=values.hex(),
            capture_output=True,
            text=True,
            timeout=timeout,
            env=env,
            preexec_fn=_limit,
        )
    except subprocess.TimeoutExpired:
        raise AssertionError(f"decode of {len(values)} value bytes took over {timeout} s") from None
    assert result.returncode == 0, result.stderr[-2000:]
    return json.loads(result.stdout)  # type: ignore[no-any-return]


MATRIX, LIST, NONE, INT = 18, 17, 0, 15
SEP = b"\n"


def test_a_matrix_of_65535_rows_by_0_columns_is_refused_before_it_is_built() -> None:
    """1,000 values of 5 bytes each claiming 65,535 empty rows (65 M rows, > 2.9 GB before)."""
    bomb = (bytes([MATRIX]) + (65535).to_bytes(2, "big") + (0).to_bytes(2, "big") + SEP) * 1000
    out = decode_in_child(bomb)
    assert out.get("field") == "variable_values", out
    assert "65535 rows" in str(out["error"]) and out["offset"] == 21, out  # after the first value's dims
    assert int(out["peak"]) < 2 << 20, out  # nothing built: well under 2 MB
    assert float(out["seconds"]) < 5, out


def test_a_count_whose_elements_cannot_fit_names_count_and_bytes_left() -> None:
    """A 65,535 x 65,535 matrix in 10 bytes: refused at its dimensions, naming both numbers."""
    bomb = bytes([MATRIX]) + (65535).to_bytes(2, "big") * 2 + b"\x00" * 5 + SEP
    out = decode_in_child(bomb)
    assert out["offset"] == 21 and out["field"] == "variable_values", out
    assert "4294836225 elements" in str(out["error"]), out
    assert out["actual"] == "6 bytes left", out


@pytest.mark.slow  # long end to end: CI runs it (RTDE_SPEC_SLOW=1), the fast loop does not
def test_empty_rows_of_many_small_matrices_stay_within_the_message_size() -> None:
    """Each matrix's rows fit its own bytes left, but together they would be quadratic:
    12,000 matrices of 60,000 empty rows are refused by the message's budget."""
    bomb = (bytes([MATRIX]) + (60000).to_bytes(2, "big") + (0).to_bytes(2, "big") + SEP) * 12000
    out = decode_in_child(bomb)
    assert "empty rows" in str(out.get("error")), out
    assert int(out["peak"]) < 8 << 20, out
    # what a program holds still decodes: a 2 x 3 matrix, 0 x 5, 3 x 0, an empty list
    cell = bytes([INT]) + (7).to_bytes(4, "big")
    values = (
        bytes([MATRIX])
        + (2).to_bytes(2, "big")
        + (3).to_bytes(2, "big")
        + cell * 6
        + SEP
        + bytes([MATRIX])
        + (0).to_bytes(2, "big")
        + (5).to_bytes(2, "big")
        + SEP
        + bytes([MATRIX])
        + (3).to_bytes(2, "big")
        + (0).to_bytes(2, "big")
        + SEP
        + bytes([LIST])
        + (0).to_bytes(2, "big")
        + SEP
    )
    assert decode_in_child(values).get("count") == 4


@pytest.mark.slow  # long end to end: CI runs it (RTDE_SPEC_SLOW=1), the fast loop does not
def test_small_values_cost_a_small_multiple_of_their_bytes() -> None:
    """The cheapest elements on the wire: a 1 MB list of NONE values (one byte each) and
    of INT values (five bytes each) decode at under 30x / 80x their bytes (490x before)."""
    nones = (bytes([LIST]) + (65000).to_bytes(2, "big") + bytes([NONE]) * 65000 + SEP) * 15
    out = decode_in_child(nones)
    assert out.get("count") == 15, out
    assert int(out["peak"]) < 30 * int(out["size"]), out
    ints = (
        bytes([LIST]) + (30000).to_bytes(2, "big") + (bytes([INT]) + b"\x00\x00\x00\x07") * 30000 + SEP
    ) * 6
    out = decode_in_child(ints)
    assert out.get("count") == 6, out
    assert int(out["peak"]) < 80 * int(out["size"]), out
