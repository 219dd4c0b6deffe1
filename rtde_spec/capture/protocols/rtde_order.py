"""The two directions of an RTDE connection put back in the order they depend on each other.

A capture merged from two capture points (mergecap) or taken on a host whose NIC queues'
clocks differ can hold the controller's reply before the client's request it answers (a
setup reply carries only types and the recipe id; the names are in the request), or a
client's package before the reply it depends on (the protocol version decides how it
decodes; an input setup reply, which recipe its data packages carry). Each direction's
bytes are in TCP order (tcp.py); only how the two interleave is put right here, before
the session decoder pairs requests with replies:

- a controller reply waits for the client's request it answers, and the controller's
  packages after it wait behind it;
- while a request is unanswered, the client's next request waits for the answer (the
  controller answers each in turn), all its packages wait while the version request is
  unanswered, and its data packages while an input setup is.

In an in-order capture nothing waits. What waits is bounded per connection: HOLD_PACKAGES
packages, HOLD_BYTES bytes (plus the one package that went past), HOLD_SECONDS of capture time.
Past any bound, or at the end of the capture, the oldest package waiting is decoded without
what it waits for, as an in-order capture missing it would be (a setup reply without its
request: the data need --recipe), and the notes say so. Nothing is dropped.
"""

from __future__ import annotations

from collections import deque

from rtde_spec._generated.constants import (
    DATA_PACKAGE_PREFIX_OFFSETS,
    DATA_PACKAGE_TYPE,
    RTDE_PACKAGE_TYPES,
    RTDE_PACKAGES,
)
from rtde_spec.rtde.packages import SETUP_REQUESTS, VERSION_REQUEST

HOLD_PACKAGES = 4096  # packages waiting per connection (8 s of 500 Hz outputs)
HOLD_BYTES = 1 << 20  # bytes waiting per connection, as TCP reassembly holds behind a hole
HOLD_SECONDS = 5.0  # capture time a package waits: clock skews between capture points are ms
TYPE_AT = DATA_PACKAGE_PREFIX_OFFSETS[1]
SENDERS = "client", "controller"

Released = tuple[str, bytes, float]  # sender, package, capture time: in the order to decode


def _answered() -> frozenset[int]:
    """The package types whose controller package answers the client's (the spec's `<request>_reply`)."""
    return frozenset(
        code
        for (code, sender, version), name in RTDE_PACKAGES.items()
        if sender == "controller" and name == f"{RTDE_PACKAGES.get((code, 'client', version))}_reply"
    )


def _code(name: str) -> int:
    """The type code of the client's package `name` (the spec's, never retyped here)."""
    return next(code for (code, sender, _), n in RTDE_PACKAGES.items() if n == name and sender == "client")


ANSWERED = _answered()
VERSION = _code(VERSION_REQUEST)
INPUTS = _code(next(name for name, direction in SETUP_REQUESTS.items() if direction == "input"))


class CausalOrder:
    """Packages of one connection in, in capture order per direction; out in the order they
    depend on each other (`take`, then `finish` at the end of the capture)."""

    def __init__(self) -> None:
        self.asked: dict[int, int] = {}  # type -> client requests let through and not yet answered
        self.held: dict[str, deque[tuple[int, bytes, float]]] = {s: deque() for s in SENDERS}
        self.count = 0  # packages held, both directions
        self.held_bytes = 0
        self.arrived = 0  # packages held so far: which of the two waiting heads came first
        self.newest = float("-inf")  # the latest capture time seen
        self.let_go: dict[tuple[str, int, str], int] = {}  # (sender, type, why) -> packages let go

    def holds(self, sender: str) -> bool:
        """Whether `sender`'s packages wait: a whole run of them must not go past."""
        return bool(self.held[sender])

    def take(self, sender: str, package: bytes, time: float) -> list[Released]:
        """The packages that may be decoded now, `package` among them when nothing holds it."""
        if time > self.newest:
            self.newest = time
        if not self.count and not self.asked and package[TYPE_AT] not in ANSWERED:
            return [(sender, package, time)]  # the common case (data): nothing waits, nothing to note
        queue = self.held[sender]
        if queue or self._waits(sender, package):
            self.arrived += 1
            queue.append((self.arrived, package, time))
            self.count += 1
            self.held_bytes += len(package)
            return self._bounded()
        self._passed(sender, package)
        if not self.count:  # the common case: nothing waits
            return [(sender, package, time)]
        return [(sender, package, time), *self._release(), *self._bounded()]

    def finish(self) -> list[Released]:
        """The end of the capture: what still waits is decoded without what it waited for."""
        out: list[Released] = []
        while self.count:
            out += self._let_go("until the end of the capture")
        return out

    def _waits(self, sender: str, package: bytes) -> bool:
        kind = package[TYPE_AT]
        if sender == "controller":
            return kind in ANSWERED and kind not in self.asked
        asked = self.asked
        return bool(asked) and (
            VERSION in asked or kind in ANSWERED or (kind == DATA_PACKAGE_TYPE and INPUTS in asked)
        )

    def _passed(self, sender: str, package: bytes) -> None:
        kind = package[TYPE_AT]
        if kind not in ANSWERED:
            return
        asked = self.asked
        if sender == "client":
            asked[kind] = asked.get(kind, 0) + 1
        elif kind in asked:
            asked[kind] -= 1
            if not asked[kind]:
                del asked[kind]

    def _release(self) -> list[Released]:
        """Every waiting package that waits no more, both directions, until none moves."""
        out: list[Released] = []
        moved = True
        while moved:
            moved = False
            for sender, queue in self.held.items():
                while queue and not self._waits(sender, queue[0][1]):
                    out.append(self._pop(sender))
                    moved = True
        return out

    def _pop(self, sender: str) -> Released:
        _, package, time = self.held[sender].popleft()
        self.count -= 1
        self.held_bytes -= len(package)
        self._passed(sender, package)
        return (sender, package, time)

    def _bounded(self) -> list[Released]:
        out: list[Released] = []
        while self.count:
            oldest = min(queue[0][2] for queue in self.held.values() if queue)
            if self.count > HOLD_PACKAGES:
                why = f"until {HOLD_PACKAGES} packages waited"
            elif self.held_bytes > HOLD_BYTES:
                why = f"until {HOLD_BYTES} bytes waited"
            elif self.newest - oldest > HOLD_SECONDS:
                why = f"{HOLD_SECONDS:g} s of capture time"
            else:
                break
            out += self._let_go(why)
        return out

    def _let_go(self, why: str) -> list[Released]:
        """The first package waiting goes on without what it waits for; then all that can follow."""
        sender = min((s for s in SENDERS if self.held[s]), key=lambda s: self.held[s][0][0])
        package = self.held[sender][0][1]
        kind = package[TYPE_AT]
        if sender == "client":  # the answers it waited for are not in the capture
            kind = VERSION if VERSION in self.asked else next(iter(self.asked))
            self.asked.clear()
        key = (sender, kind, why)
        self.let_go[key] = self.let_go.get(key, 0) + 1
        return [self._pop(sender), *self._release()]

    def notes(self) -> list[str]:
        """What was decoded without its other half, and after how long: one line per sender and bound."""
        kinds: dict[tuple[str, str], list[str]] = {}
        for (sender, kind, why), times in self.let_go.items():
            name = RTDE_PACKAGE_TYPES.get(kind, str(kind))
            kinds.setdefault((sender, why), []).append(name if times == 1 else f"{name} x{times}")
        out = []
        for (sender, why), names in kinds.items():
            what = (
                "controller replies without their request"
                if sender == "controller"
                else "client requests without their reply"
            )
            after = "" if sender == "controller" else "the client's packages after each "
            out.append(f"{what} ({', '.join(names)}): {after}decoded without it after waiting {why}")
        return out
