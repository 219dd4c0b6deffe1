"""Which connection a segment belongs to, and how long its state is kept (the routing stage).

A capture can hold millions of connections: a port scan's SYNs, a fleet reconnecting
all day. State is kept only while it can matter: a connection we decode is finished
(its tables written, its summary kept) `LINGER_SECONDS` of capture time after its FIN
or RST, so late retransmissions still reach it, or after `IDLE_SECONDS` without a
segment; a connection we do not decode keeps nothing but a bounded cache entry
saying so, and SYNs waiting for their first data to say what they are are bounded too.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from rtde_spec.capture.protocols.base import ConnectionDecoder
from rtde_spec.capture.protocols.opening import content_kind
from rtde_spec.capture.protocols.rtde import RTDE_HEADER
from rtde_spec.capture.reading.packets import FIN, RST, SYN, Segment
from rtde_spec.capture.routing.classify import ROBOT_CLIENT_KINDS, connection_for
from rtde_spec.capture.tables.sink import TableSink
from rtde_spec.capture.tables.summary import ConnectionSummary
from rtde_spec.capture.tcp import MOD, Direction
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.packages import encode_package

# how an RTDE client opens: the header of a protocol version request (its size and type)
RTDE_VERSION_REQUEST = encode_package("request_protocol_version", {"protocol_version": 2})[:RTDE_HEADER]
SCRIPT_KIND = "urcl-script"  # the script sender's connections: finished first (their programs are read)
LINGER_SECONDS = 5.0  # after FIN/RST: retransmissions still arrive within a few RTOs
IDLE_SECONDS = 900.0  # a decoded connection silent this long is finished (a new one may follow)
SWEEP_SECONDS = 1.0  # how often (capture time) closing and idle connections are looked at
MAX_FOREIGN = 1 << 16  # connections remembered as not ours
MAX_LISTED = 1000  # finished connections listed one by one in the summary; the rest are folded
MAX_FOLDED_LINES = 1000  # problems and notes kept word for word on a folded line
MAX_PENDING_SYNS = 1 << 14  # SYNs of connections on unknown ports, waiting for their first data
REUSE_MARK = "#"  # `connection` of the 2nd, 3rd... connection on one 4-tuple: "A:p-B:q #2"


@dataclass
class Flow:
    client: tuple[str, int]
    server: tuple[str, int]
    kind: str
    decoder: ConnectionDecoder
    directions: dict[str, Direction] = field(
        default_factory=lambda: {"client": Direction(), "controller": Direction()}
    )
    last: float = 0.0  # capture time of its last segment
    closed_at: float | None = None  # capture time of its first FIN or RST


Route = tuple[Flow, str, Direction]  # the flow, who sends, and that sender's direction
Key = frozenset[tuple[str, int]]


class FlowTable:
    """The connections of one capture: routes segments, finishes connections that are done."""

    def __init__(self, classify: Callable[[Segment, str], Flow | None]) -> None:
        self._classify = classify
        self.flows: dict[Key, Flow] = {}
        self.routes: dict[tuple[str, int, str, int], Route] = {}
        self.foreign: OrderedDict[Key, None] = OrderedDict()
        self.pending: OrderedDict[Key, list[Segment]] = OrderedDict()  # SYNs on unknown ports
        self.finished: list[ConnectionSummary] = []
        self.folded: dict[str, ConnectionSummary] = {}  # past MAX_LISTED: one line per kind
        self.script_first: list[Flow] = []
        self.reopened: list[Flow] = []  # closed connections whose 4-tuple a new SYN took: finished first
        self.uses: dict[Key, int] = {}  # how many connections a reused 4-tuple has carried
        self._swept = float("-inf")

    def route_of(self, seg: Segment) -> Route | None:
        """The segment's route, or None: not a connection we decode (or a SYN still undecided)."""
        route = self.routes.get((seg.src, seg.sport, seg.dst, seg.dport))
        if route is not None and seg.flags & SYN and _new_connection(route, seg):
            self._retire(route[0])
            route = None
        if route is None:
            route = self._new_route(seg)
            if route is None:
                return None
        flow = route[0]
        flow.last = seg.time
        if seg.flags & (FIN | RST) and flow.closed_at is None:
            flow.closed_at = seg.time
        if seg.ack >= 0:
            _acked(flow, "client" if route[1] == "controller" else "controller", seg.ack)
        return route

    def _new_route(self, seg: Segment) -> Route | None:
        key: Key = frozenset({(seg.src, seg.sport), (seg.dst, seg.dport)})
        flow = self.flows.get(key)
        if flow is None:
            if key in self.foreign:
                return None
            uses = self.uses.get(key)  # a reused 4-tuple's later connections: named apart
            flow = self._classify(seg, f" {REUSE_MARK}{uses}" if uses is not None else "")
            if flow is None:
                if not seg.payload:
                    if seg.flags & SYN:  # kept: the stream starts here if its first data says what it is
                        self.pending.setdefault(key, []).append(seg)
                        if len(self.pending) > MAX_PENDING_SYNS:
                            self.pending.popitem(last=False)  # a scan: its oldest handshakes forgotten
                    return None
                self.pending.pop(key, None)
                self.foreign[key] = None
                if len(self.foreign) > MAX_FOREIGN:
                    self.foreign.popitem(last=False)
                return None
            self.flows[key] = flow
            for syn in self.pending.pop(key, []):
                side = "client" if (syn.src, syn.sport) == flow.client else "controller"
                flow.directions[side].feed(syn.time, syn.seq, b"", syn=True)
        sender = "client" if (seg.src, seg.sport) == flow.client else "controller"
        route = (flow, sender, flow.directions[sender])
        self.routes[(seg.src, seg.sport, seg.dst, seg.dport)] = route
        return route

    def _retire(self, flow: Flow) -> None:
        """A closed connection whose addresses and ports a new one reuses: no segment reaches it
        any more; it is finished at the next sweep (`due` says so at once)."""
        key: Key = frozenset({flow.client, flow.server})
        self.flows.pop(key, None)
        self.uses[key] = self.uses.get(key, 1) + 1
        (a, b) = (flow.client, flow.server)
        self.routes.pop((a[0], a[1], b[0], b[1]), None)
        self.routes.pop((b[0], b[1], a[0], a[1]), None)
        self.reopened.append(flow)

    def due_from(self) -> float:
        """The capture time from which `due` is true (minus infinity while reopened ones wait)."""
        return float("-inf") if self.reopened else self._swept + SWEEP_SECONDS

    def due(self, now: float) -> bool:
        """Whether it is time to look for connections to finish (cheap: one comparison)."""
        return bool(self.reopened) or now - self._swept >= SWEEP_SECONDS

    def sweep(self, now: float, finish: Callable[[Flow], None]) -> None:
        """Finish the connections closed LINGER_SECONDS ago or idle IDLE_SECONDS; drop their state."""
        self._swept = now
        while self.reopened:
            flow = self.reopened.pop(0)
            finish(flow)
            self._keep(connection_summary(flow))
        done = [
            (key, flow)
            for key, flow in self.flows.items()
            if (flow.closed_at is not None and now - flow.closed_at > LINGER_SECONDS)
            or now - flow.last > IDLE_SECONDS
        ]
        for key, flow in done:
            finish(flow)
            self._keep(connection_summary(flow))
            del self.flows[key]
            (a, b) = (flow.client, flow.server)
            self.routes.pop((a[0], a[1], b[0], b[1]), None)
            self.routes.pop((b[0], b[1], a[0], a[1]), None)

    def _keep(self, summary: ConnectionSummary) -> None:
        """The first MAX_LISTED finished connections are listed; the rest fold into one line per kind."""
        if len(self.finished) < MAX_LISTED:
            self.finished.append(summary)
            return
        folded = self.folded.get(summary.kind)
        if folded is None:
            folded = self.folded[summary.kind] = ConnectionSummary(
                "", summary.kind, 0, 0, 0, [], {}, notes=[]
            )
        fold(folded, summary)

    def summaries(self) -> list[ConnectionSummary]:
        """Every connection's summary: finished ones, folded ones, then those still open."""
        for flow in self.live():  # at the end: those still open count like the finished
            self._keep(connection_summary(flow))
        self.reopened.clear()
        self.flows.clear()
        self.routes.clear()
        for kind, folded in self.folded.items():
            folded.name = f"{folded.folded} more {kind} connections"
        return [*self.finished, *self.folded.values()]

    def live(self) -> list[Flow]:
        return [*self.reopened, *self.flows.values()]


def _acked(flow: Flow, other: str, ack: int) -> None:
    """What the other direction's holes before `ack` held was never captured: what waits behind
    them goes to the decoder now, before this segment, as it was sent. Not in a connection that
    shows copies of its segments: from a second capture point (mergecap) a segment the first
    one missed comes a few ms after the acknowledgment, and fills the hole as it is."""
    direction = flow.directions[other]
    if direction.waiting and not any(d.copies for d in flow.directions.values()):
        for chunk in direction.acked(ack):
            flow.decoder.feed(other, chunk)


def _new_connection(route: Route, seg: Segment) -> bool:
    """Whether a SYN starts a new connection on the 4-tuple of a closed one (a client that binds
    its port, or reconnects after a reset): not the SYN of this one seen again."""
    flow, _, direction = route
    return flow.closed_at is not None and direction.base not in (None, (seg.seq + 1) % MOD)


def fold(into: ConnectionSummary, one: ConnectionSummary) -> None:
    """Add one connection's counts to a line that stands for many (problems kept up to a bound)."""
    into.folded += 1
    into.packages += one.packages
    into.gaps += one.gaps
    into.lost_bytes += one.lost_bytes
    into.skipped_bytes += one.skipped_bytes
    into.cut_packages += one.cut_packages
    into.lead_in_bytes += one.lead_in_bytes
    into.conflicts += one.conflicts
    into.conflict_bytes += one.conflict_bytes
    for size, count in one.unknown_recipe_sizes.items():
        into.unknown_recipe_sizes[size] = into.unknown_recipe_sizes.get(size, 0) + count
    room = MAX_FOLDED_LINES - len(into.errors)
    into.errors += [f"{one.name}: {e}" for e in one.errors[:room]]
    for note in one.notes:
        if note not in into.notes and len(into.notes) < MAX_FOLDED_LINES:
            into.notes.append(note)


def classify(
    seg: Segment,
    sink: TableSink,
    recipe: RecipeCodec | None,
    ports: Mapping[int, str],
    cat: Catalogue,
    session: dict[str, Any],
    mark: str = "",
) -> Flow | None:
    """A new connection's protocol, by port or by its first data; None when it is none of ours.
    `mark` follows its name where its 4-tuple carried a connection before (" #2")."""
    src, dst = (seg.src, seg.sport), (seg.dst, seg.dport)
    if seg.dport in ports:
        client, server, kind = src, dst, ports[seg.dport]
    elif seg.sport in ports:
        client, server, kind = dst, src, ports[seg.sport]
    elif seg.payload.startswith(RTDE_VERSION_REQUEST):
        client, server, kind = src, dst, "rtde"  # RTDE on another port, recognised by its first request
    elif (found := content_kind(seg.payload)) is not None:
        client, server, kind = dst, src, found  # the controller speaks first: its first message
    else:
        return None
    name = f"{client[0]}:{client[1]}-{server[0]}:{server[1]}{mark}"
    decoder = connection_for(
        kind, name, client[0], server[0], sink, recipe=recipe, catalogue=cat, session=session
    )
    label = f"urcl-{kind}" if kind in ROBOT_CLIENT_KINDS else kind
    return Flow(client, server, label if kind != "script_sender" else SCRIPT_KIND, decoder)


def connection_summary(flow: Flow) -> ConnectionSummary:
    """What one connection gave and lost, kept after its state is dropped."""
    counts = flow.decoder.counts
    framings = flow.decoder.framings().values()
    directions = flow.directions.values()
    return ConnectionSummary(
        flow.decoder.name,
        flow.kind,
        counts.packages,
        sum(d.gaps for d in directions),
        sum(d.lost_bytes for d in directions),
        counts.errors.lines(),
        counts.unknown_recipe_sizes,
        skipped_bytes=sum(f.skipped for f in framings),
        cut_packages=sum(f.cut for f in framings),
        lead_in_bytes=sum(f.lead_in for f in framings),
        notes=list(getattr(flow.decoder, "notes", ())),
        conflicts=sum(d.conflicts for d in directions),
        conflict_bytes=sum(d.conflict_bytes for d in directions),
    )
