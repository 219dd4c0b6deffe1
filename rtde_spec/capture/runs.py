"""Runs: the one place where data segments are batched, whole packages of one recipe in order.

At 500 Hz nearly every segment of an RTDE capture is exactly one data package of one
recipe. `Batcher` takes each routed segment (or a whole bulk item the reader found with
numpy) and either extends the current run, or flushes it and goes segment by segment
through TCP reassembly and framing. A run is decoded in one `decode_many` by the RTDE
decoder (`feed_run`); a run too short to pay goes the per-segment way.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rtde_spec._generated.constants import DATA_PACKAGE_TYPE
from rtde_spec.capture.protocols.rtde import RtdeConnection
from rtde_spec.capture.reading.bulk import SIZE_AT, SIZE_BYTES, TYPE_AT
from rtde_spec.capture.reading.packets import FIN, RST, SYN, Segment, expand, first_of
from rtde_spec.capture.routing.flows import FlowTable, Route
from rtde_spec.capture.tcp import MOD, RECENT
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec

RUN_HEAD = PAYLOAD_OFFSET  # size, type, recipe id: the bytes every data package of one run shares
RUN_MIN, RUN_MAX = 16, 4096  # shorter runs go segment by segment; longer ones are cut


class Batcher:
    """Routes segments and bulk items of one capture to their connections, batching runs.

    A run is held per connection direction (HELD at most): a control session's inputs
    between its outputs, or another connection's segments, do not end it, as in the bulk
    reading (`bulk.runs`). Anything else of its connection flushes that connection's runs
    first, so each connection's segments reach it in order.
    """

    HELD = 8  # runs held at once (each up to RUN_MAX segments): many connections, bounded memory

    def __init__(self, table: FlowTable, finish: Any) -> None:
        self.table, self.finish = table, finish
        self.held: dict[int, Run] = {}  # by id of the run's direction: data segments, in order
        self.swept_later: list[Any] = []  # capture times of bulk runs' packages not yet swept at

    def segment(self, seg: Segment) -> None:
        if self.swept_later:
            self._sweeps_before(seg.time)
        route = self.table.route_of(seg)
        if route is None:
            return
        held = self.held
        run = Run.start(route, seg) if id(route[2]) not in held else None
        if held:
            same = held.get(id(route[2]))
            if same is not None and same.takes(route, seg):
                return
            flow = route[0]
            mine = [key for key, other in held.items() if other.route[0] is flow]
            if mine and _bare(seg) and not self.table.due(seg.time):
                return  # the connection's ACK between its packages: nothing to deliver, its runs go on
            if run is None:  # anything but a run of its own direction beginning: after its runs
                for key in mine:
                    held.pop(key).flush()
                run = Run.start(route, seg) if same is not None else None
        if run is None:
            feed(route, seg)
        else:
            if len(held) >= self.HELD:
                held.pop(next(iter(held))).flush()  # the oldest
            held[id(route[2])] = run
        if self.table.due(seg.time):
            self.flush()
            self.table.sweep(seg.time, self.finish)

    def bulk(self, item: Any) -> None:
        """A block of same-shaped data segments the reader found at once: whole, or one by one."""
        first = first_of(item)
        if self.swept_later:
            self._sweeps_before(first.time)
        route = self.table.route_of(first)
        self.flush()  # segments held first, so the direction is where this run starts
        if route is not None and _peer_waits(route):  # its acknowledgments are read in their places
            route = None
        if route is not None and route[0].kind != "rtde" and _records_whole(route, first, item):
            self._sweep_later(item.times)
            return
        whole = Run.start(route, first) if route is not None else None
        if whole is None:
            for seg in expand(item):  # not a run this connection can take whole: segment by segment
                self.segment(seg)
            return
        flow, sender, direction = whole.route
        flow.last = float(item.times[-1])
        direction.advance(item.rows.size, _tail(item.rows), item.rows.shape[1])
        whole.decoder.feed_run(sender, whole.codec, item.rows, item.times)
        self._sweep_later(item.times)

    def _sweep_later(self, times: Any) -> None:
        """A bulk run's packages, each of which the frame-by-frame reading would follow with a
        sweep when one is due (`FlowTable.due`): the segments of other connections inside its
        span come after it here, so those sweeps are made before each of them, at the times
        they would have been (`_sweeps_before`)."""
        if len(times) and times[-1] >= self.table.due_from():
            self.swept_later.append(times)  # (a view of the block's times, in time order)

    def _sweeps_before(self, now: float) -> None:
        """The sweeps due at bulk runs' packages up to `now`, in time order: a connection idle or
        closed long enough by then is finished before a segment of it comes (and begins a new one)."""
        if now < self.table.due_from():
            return  # none due yet: the usual case (one sweep a second of capture time)
        import numpy as np

        while True:
            since = self.table.due_from()
            due = [t[k] for t in self.swept_later if (k := int(np.searchsorted(t, since))) < len(t)]
            at = min(due, default=now + 1)
            if at > now:
                break
            self.flush()
            self.table.sweep(float(at), self.finish)
        since = self.table.due_from()
        self.swept_later = [t for t in self.swept_later if t[-1] > now and t[-1] >= since]

    def flush(self) -> None:
        held = self.held
        while held:
            held.pop(next(iter(held))).flush()


_NOT_DATA = SYN | FIN | RST


def _bare(seg: Segment) -> bool:
    """A segment with no data and no SYN, FIN or RST (an ACK, a window update): routing it
    (`FlowTable.route_of`) is all it does. The peer of a 500 Hz stream sends one after nearly
    every package, so a capture taken on either host has them between the packages of a run."""
    return not seg.payload and not seg.flags & _NOT_DATA


def _peer_waits(route: Route) -> bool:
    """Whether the other direction holds segments behind a hole: each segment of this one may
    acknowledge past it (`FlowTable.route_of`), so it is read segment by segment."""
    flow, sender, _ = route
    return bool(flow.directions["client" if sender == "controller" else "controller"].waiting)


def _records_whole(route: Route, first: Segment, item: Any) -> bool:
    """A run of one-size records (URCL's external control, the real-time interface) to a decoder
    that takes them whole (`feed_rows`), in order with nothing waiting; False: segment by segment."""
    flow, sender, direction = route
    take = getattr(flow.decoder, "feed_rows", None)
    if take is None or not direction.in_order_at(first.seq) or not take(sender, item.rows, item.times):
        return False
    flow.last = float(item.times[-1])
    direction.advance(item.rows.size, _tail(item.rows), item.rows.shape[1])
    return True


def _tail(rows: Any) -> bytes:
    """The last bytes of a run's packages `Direction.advance` may keep (2 x RECENT)."""
    return rows[-(2 * RECENT // rows.shape[1] + 1) :].tobytes()  # type: ignore[no-any-return]


def feed(route: Route, seg: Segment) -> None:
    flow, sender, direction = route
    for chunk in direction.feed(seg.time, seg.seq, seg.payload, syn=bool(seg.flags & SYN)):
        flow.decoder.feed(sender, chunk)


@dataclass
class Run:
    """Consecutive segments of one direction, each exactly one data package of one recipe.

    At 500 Hz that is nearly every segment of an RTDE capture; they skip reassembly and
    framing one by one and are decoded in one `decode_many` (its prefix check still
    covers every package). A run too short to pay goes the per-segment way.
    """

    route: Route
    decoder: RtdeConnection
    codec: RecipeCodec
    head: bytes  # size, type and recipe id every package of the run starts with
    next_seq: int
    segments: list[Segment]

    @classmethod
    def start(cls, route: Route, seg: Segment) -> Run | None:
        flow, sender, direction = route
        payload = seg.payload
        if flow.kind != "rtde" or seg.flags & _NOT_DATA or len(payload) <= RUN_HEAD:
            return None
        size = int.from_bytes(payload[SIZE_AT : SIZE_AT + SIZE_BYTES], "big")
        if payload[TYPE_AT] != DATA_PACKAGE_TYPE or size != len(payload):
            return None
        decoder = flow.decoder
        if not direction.in_order_at(seg.seq) or not isinstance(decoder, RtdeConnection):
            return None
        codec = decoder.run_codec(sender, payload)
        if codec is None:
            return None
        decoder.name_table(sender, codec)
        return cls(route, decoder, codec, payload[:RUN_HEAD], (seg.seq + len(payload)) % MOD, [seg])

    def takes(self, route: Route, seg: Segment) -> bool:
        """Add the segment if it continues the run; False when it does not."""
        payload = seg.payload
        if (
            route is not self.route
            or seg.seq != self.next_seq
            or len(payload) != self.codec.package_size
            or seg.flags & _NOT_DATA
            or payload[:RUN_HEAD] != self.head
            or len(self.segments) >= RUN_MAX
        ):
            return False
        self.segments.append(seg)
        self.next_seq = (self.next_seq + len(payload)) % MOD
        return True

    def flush(self) -> None:
        if len(self.segments) < RUN_MIN:
            for seg in self.segments:
                feed(self.route, seg)
            return
        _, sender, direction = self.route
        import numpy as np

        data = b"".join(s.payload for s in self.segments)
        direction.advance(len(data), data[-2 * RECENT :], len(self.segments[0].payload))
        rows = np.frombuffer(data, dtype=np.uint8).reshape(len(self.segments), -1)
        self.decoder.feed_run(sender, self.codec, rows, np.array([s.time for s in self.segments]))
