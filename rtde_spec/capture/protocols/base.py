"""What every protocol decoder of a capture is: the ConnectionDecoder protocol, its counts and problems.

One decoder per TCP connection, chosen by `routing/classify.py`; the pipeline feeds it
each direction's reassembled chunks, asks for its framings' losses at the end, and sums
its counts into the summary. RTDE's decoder also takes whole runs of data packages
(`run_codec` / `feed_run`), batched by `capture/decoder.py`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from collections.abc import Mapping

    from rtde_spec.capture.tcp import Chunk


class Problems(list[str]):
    """A connection's problems: the first MAX_PROBLEMS kept word for word, the rest only counted,
    so a capture of a million bad packages costs a number, not a million strings."""

    def __init__(self) -> None:
        super().__init__()
        self.more = 0

    def append(self, problem: str) -> None:
        if len(self) < MAX_PROBLEMS:
            super().append(problem)
        else:
            self.more += 1

    def lines(self) -> list[str]:
        more = [f"... {self.more} more problems of this connection, not listed"] if self.more else []
        return [*self, *more]


MAX_PROBLEMS = 1000


@dataclass
class Counts:
    packages: int = 0
    errors: Problems = field(default_factory=Problems)
    unknown_recipe_sizes: dict[int, int] = field(default_factory=dict)  # data package size -> count


class FramingState(Protocol):
    """What the summary reads of a direction's framing: bytes held, skipped, cut, lead-in."""

    @property
    def buf(self) -> bytearray: ...
    @property
    def skipped(self) -> int: ...
    @property
    def cut(self) -> int: ...
    @property
    def lead_in(self) -> int: ...


class ConnectionDecoder(Protocol):
    """One connection's decoder: chunks in (per direction, in capture order), rows to the sink."""

    name: str
    counts: Counts

    def feed(self, sender: str, chunk: Chunk) -> None:
        """Take the next reassembled bytes `sender` ("client" or "controller") sent."""

    def finish(self) -> None:
        """The capture ended: decode what the framings still hold."""

    def framings(self) -> Mapping[str, FramingState]:
        """Each direction's framing (what it skipped and lost goes into the summary)."""
        ...

    def close(self) -> None:
        """Flush what is batched to the sink."""


def server_port(name: str) -> str:
    """The server's port of a connection's name ("A:p-B:q", "A:p-B:q #2" on a reused 4-tuple)."""
    return name.split(" ", 1)[0].rpartition(":")[2]
