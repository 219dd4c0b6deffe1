"""Cut URScript arriving on a primary/secondary port into what a controller runs.

A controller runs a line sent outside a program as soon as its newline arrives, and
a `def` (or `sec`) program once its closing `end` has; a line without its newline is
not run yet. Blocks are counted by their keywords outside strings and comments, wherever
they stand: a condition may go on over lines (Robotiq's vacuum URCap writes
`while (not a(s) and` / `b(s)):`), a string may hold `#`, and `if x: y() end` opens and
closes on one line. Bytes that cannot be URScript text (invalid UTF-8, NUL and other control
bytes) are refused, and what is held unfinished is counted so the server can bound it.
"""

from __future__ import annotations

import re

from rtde_spec.emulator.ports.guard import GuardedConnection, Port
from rtde_spec.errors import ProtocolError

_NOT_TEXT = re.compile(rb"[\x00-\x08\x0b\x0e-\x1f\x7f]")
_STRINGS = re.compile(r"\"(?:[^\"\\\n]|\\.)*\"|'(?:[^'\\\n]|\\.)*'")
# keywords open (and `end` closes) one block each; after a `.` they are a struct's field (time().sec)
_OPENS = re.compile(r"(?<![.\w])(?:def|sec|thread|if|while)\b")
_ENDS = re.compile(r"(?<![.\w])end\b")


class ScriptFramer:
    """Feed bytes as they arrive; each call returns the scripts completed (lines or programs)."""

    def __init__(self) -> None:
        self._held = bytearray()  # the unfinished last line
        self._program: list[str] = []  # lines of a program whose `end` has not come
        self._program_bytes = 0
        self._depth = 0

    @property
    def pending(self) -> int:
        """Bytes held that are not a whole script yet."""
        return len(self._held) + self._program_bytes

    def feed(self, data: bytes) -> list[str]:
        """Scripts completed by `data`, in order; ProtocolError for bytes that are no URScript."""
        bad = _NOT_TEXT.search(data)
        if bad is not None:
            raise ProtocolError(
                "bytes that are no URScript text",
                offset=bad.start(),
                actual=f"0x{data[bad.start()]:02x}",
            )
        self._held += data
        if b"\n" not in data:  # the held line goes on: what came before is not searched again
            return []
        cut = self._held.rfind(b"\n")
        if cut < 0:
            return []
        whole = bytes(self._held[: cut + 1])
        del self._held[: cut + 1]
        try:
            text = whole.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ProtocolError("bytes that are no UTF-8 text", offset=exc.start) from None
        return self._scripts(text.splitlines())

    def _scripts(self, lines: list[str]) -> list[str]:
        out: list[str] = []
        loose: list[str] = []  # lines outside any program, run together
        for line in lines:
            code = _STRINGS.sub('""', line).split("#", 1)[0].strip()
            opens = len(_OPENS.findall(code))
            net = opens - len(_ENDS.findall(code))
            if self._depth == 0 and net <= 0:  # a line of its own, blocks and all
                if code:
                    loose.append(line)
                continue
            if self._depth == 0 and loose:
                out.append("\n".join(loose) + "\n")
                loose = []
            self._depth = max(0, self._depth + net)
            self._program.append(line)
            self._program_bytes += len(line) + 1
            if self._depth == 0:
                out.append("\n".join(self._program) + "\n")
                self._program, self._program_bytes = [], 0
        if loose:
            out.append("\n".join(loose) + "\n")
        return out


class ScriptPort(GuardedConnection):
    """A client of a port that takes URScript (primary, secondary, real-time): its bytes framed
    into scripts within the port's limits, each handed to `run_script`; read-only ports ignore
    what clients send. Subclasses set `read_only` and `number` and say how a script runs."""

    read_only: bool
    number: int

    def __init__(self, port: Port) -> None:
        super().__init__(port)
        self.framer = ScriptFramer()

    def run_script(self, text: str) -> None:
        raise NotImplementedError

    def data_received(self, data: bytes) -> None:
        if self.read_only or self.dropped:
            return  # a read-only port ignores what clients send
        try:
            scripts = self.framer.feed(data)
        except ProtocolError as exc:
            self.drop(f"sent {exc}")
            return
        if self.received(self.framer.pending, len(scripts)):
            for text in scripts:
                self.run_script(text)
