"""Records of dashboard server connections (port 29999): one row per request with its reply.

Requests and replies are lines; each reply answers the oldest request still open
(the server answers in order). The command, its argument and which of the spec's
reply texts the reply is (ok, failed, not_found, unknown) come from
spec/dashboard/commands.yaml; the latency is the capture time between the request's
segment and the reply's. The greeting is a row of its own (request empty).
"""

from __future__ import annotations

from collections import deque
from typing import Any

from rtde_spec.capture.framing.lines import LineFraming
from rtde_spec.capture.protocols.base import Counts
from rtde_spec.capture.tables.rows import text_columns
from rtde_spec.capture.tables.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.metamodel.dashboard import dashboard_spec

TABLE = "dashboard"


class DashboardConnection:
    def __init__(self, name: str, robot: str, sink: TableSink) -> None:
        self.name, self.robot, self.sink = name, robot, sink
        self.spec = dashboard_spec()
        limit = self.spec.max_line_bytes
        self.framing = {
            "client": LineFraming(limit, self._whole_request),
            "controller": LineFraming(limit, self._whole_reply),
        }
        self.open: deque[tuple[float, str]] = deque()
        self.greeted = False
        self.after_gap = False  # bytes of the server were lost since its replies last matched
        self.counts = Counts()
        self.last_time = 0.0

    def feed(self, sender: str, chunk: Chunk) -> None:
        self.last_time = chunk.time
        if sender == "controller" and chunk.gap_before:
            self.after_gap = True
        for line in self.framing[sender].feed(chunk):
            self._line(sender, line, chunk.time)

    def _whole_request(self, raw: bytes) -> bool:
        """Whether a line after a gap in the client's bytes is a whole request (a command's)."""
        return self.spec.find(raw.decode("utf-8", "replace")) is not None

    def _whole_reply(self, raw: bytes) -> bool:
        """Whether a line after a gap in the server's bytes is a whole line: the greeting, or a
        reply of an open request's command. Passed over, its request would take the next one's
        reply, and every request after it too (a snap length of 96 bytes cut every session's
        greeting: each row had the reply to the request after it)."""
        text = raw.decode("utf-8", "replace")
        if not self.open:
            return text == self.spec.greeting
        return any(self._answers(request, text) for _, request in self.open)

    def _answers(self, request: str, reply: str) -> bool:
        found = self.spec.find(request)
        return self.spec.outcome(found[0] if found is not None else None, reply) is not None

    def _line(self, sender: str, raw: bytes, time: float) -> None:
        text = raw.decode("utf-8", "replace")
        self.counts.packages += 1
        if sender == "client":
            self.open.append((time, text))
            return
        if self.open and self.after_gap:
            self._realign(text)
        if self.open:
            request_time, request = self.open.popleft()
            self._row(request_time, request, text, time)
        else:  # the greeting, or a line no request asked for
            self._row(time, "", text, time, "greeting" if not self.greeted else "unrequested")
        self.greeted = True

    def _realign(self, reply: str) -> None:
        """After a gap in the server's bytes, the first reply that answers an open request's command
        tells whose it is: the requests before that one had their replies in the gap (rows with
        no reply), rather than each taking the reply to the one after it."""
        answered = next((k for k, (_, r) in enumerate(self.open) if self._answers(r, reply)), None)
        if answered is None:
            return
        for _ in range(answered):
            time, request = self.open.popleft()
            self._row(time, request, "", float("nan"), "no_reply")
        self.after_gap = False

    def _row(
        self, time: float, request: str, reply: str, reply_time: float, outcome: str | None = None
    ) -> None:
        found = self.spec.find(request) if request else None
        command, argument = found if found is not None else (None, "")
        if outcome is None:
            outcome = self.spec.outcome(command, reply) or "unexpected"
        row: dict[str, Any] = {
            "connection": self.name,
            "capture_time": time,
            **text_columns("request", request),
            "command": command.command if command is not None else "",
            "argument": argument,
            **text_columns("reply", reply),
            "outcome": outcome,
            "reply_time": reply_time,
            "latency": reply_time - time,
        }
        self.sink.row(TABLE, self.robot, day_of(time), row)

    def framings(self) -> dict[str, LineFraming]:
        return self.framing

    def finish(self) -> None:
        for sender in ("client", "controller"):
            for line in self.framing[sender].finish():
                self._line(sender, line, self.last_time)
        while self.open:  # requests the capture holds no reply for
            time, request = self.open.popleft()
            self._row(time, request, "", float("nan"), "no_reply")
        for sender, framing in self.framing.items():
            if framing.too_long:
                self.counts.errors.append(
                    f"{framing.too_long} {sender} lines over {framing.limit} bytes skipped"
                )

    def close(self) -> None:
        pass
