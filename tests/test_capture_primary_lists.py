"""Primary messages whose lists vary in length from one message to the next (a program's
threads, a global variables update) keep one column set in their table: the list is one JSON
column. Spread into numbered columns, a later batch with a longer list had columns the file did
not: Parquet dropped them with no word (and now refuses such a batch outright).
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

import rtde_spec.output.parquet as parquet
from rtde_spec._generated.primary_models import ProgramThread, ProgramThreadsMessage
from rtde_spec.cli.main import main
from rtde_spec.primary.codec import encode_message

from .capture_files import Conversation, write

COUNTS = [1, 1, 3, 2, 0, 4]  # threads per message: the first batch is not the longest


def threads_message(n: int, at: int) -> bytes:
    threads = [
        ProgramThread(label_id=at * 10 + i, label_name=f"line {i}", thread_name=f"thread_{i}")
        for i in range(n)
    ]
    return encode_message(
        ProgramThreadsMessage(timestamp=at, source=-2, robot_message_type=14, threads=threads)
    )


@pytest.fixture
def small_batches(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rows go to Parquet two at a time, as a long capture's tables go 16,384 at a time."""
    monkeypatch.setattr(parquet, "_PARQUET_BATCH_ROWS", 2)


def test_threads_of_every_message_are_in_the_table(tmp_path: Path, small_batches: None) -> None:
    conv = Conversation(("192.168.56.1", 43001), ("192.168.56.101", 30001))
    conv.handshake()
    for at, n in enumerate(COUNTS):
        conv.send("server", threads_message(n, at), dt=0.1)
    pcap = write(tmp_path / "threads.pcap", [conv])
    out = tmp_path / "tables"
    assert main(["capture", str(pcap), "-o", str(out)]) == 0
    table = pq.read_table(out / "primary_program_threads_message")
    assert not [n for n in table.column_names if n.startswith("threads_")]
    threads = [json.loads(t) for t in table.column("threads").to_pylist()]
    assert [len(t) for t in threads] == COUNTS
    assert threads[3][1] == {"label_id": 31, "label_name": "line 1", "thread_name": "thread_1"}
