"""RTDE connections of a capture: the session state, setup rows, and data packages batched per recipe.

The session (protocol version, recipes from the setup exchange) is followed by
`SessionDecoder`; data packages of a known recipe are batched and decoded together, or
come as whole runs from the bulk path (`run_codec` / `feed_run`). A resynchronisation
candidate is checked against a known recipe's id and size. Packages reach the session in
the order they depend on each other (`rtde_order.py`): a merged capture can hold a setup
reply before its request.
"""

from __future__ import annotations

import json
import struct
from typing import Any

from rtde_spec._generated.constants import (
    DATA_PACKAGE_PREFIX_OFFSETS,
    DATA_PACKAGE_TYPE,
    RTDE_DIRECTIONS,
    RTDE_HEADER_FORMAT,
    RTDE_LIMITS,
    RTDE_PACKAGE_TYPES,
)
from rtde_spec.capture.framing.sized import NO, STRONG, WEAK, Check, Framing
from rtde_spec.capture.protocols.base import Counts
from rtde_spec.capture.protocols.rtde_order import CausalOrder
from rtde_spec.capture.tables.rows import wide_values
from rtde_spec.capture.tables.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.errors import RtdeSpecError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.output.base import plain
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.data_forms import implied_recipe_id
from rtde_spec.rtde.packages import DATA, TEXTS
from rtde_spec.rtde.session import SessionDecoder

BATCH = 4096
RTDE_HEADER = struct.calcsize(RTDE_HEADER_FORMAT)
_SIZE_AT, TYPE_AT, RECIPE_ID_AT = DATA_PACKAGE_PREFIX_OFFSETS
RTDE_SIZE_BYTES = TYPE_AT - _SIZE_AT  # the size field leads the header


class RtdeConnection:
    def __init__(
        self, name: str, robot: str, sink: TableSink, given: RecipeCodec | None, catalogue: Catalogue
    ) -> None:
        self.name, self.robot, self.sink, self.given = name, robot, sink, given
        self.session = SessionDecoder(catalogue=catalogue)
        types = set(RTDE_PACKAGE_TYPES)
        limit = RTDE_LIMITS["package_max_bytes"]
        self.framing = {
            s: Framing(RTDE_SIZE_BYTES, RTDE_HEADER, types, limit, self._check(s)) for s in RTDE_DIRECTIONS
        }
        self.counts = Counts()
        self.last_time = 0.0
        self.batches: dict[tuple[str, int], tuple[RecipeCodec, Any, Any]] = {}  # packages: bytes list or rows
        self.order = CausalOrder()

    @property
    def notes(self) -> list[str]:
        """Packages decoded without their other half (a reply without its request): the summary's."""
        return self.order.notes()

    def feed(self, sender: str, chunk: Chunk) -> None:
        self.last_time = chunk.time
        framing = self.framing[sender]
        self._packages(sender, framing.feed(chunk), framing.times, chunk.time)

    def _packages(self, sender: str, packages: list[bytes], times: list[float] | None, now: float) -> None:
        for n, package in enumerate(packages):
            time = now if times is None else times[n]  # a package held back: when it was completed
            self.counts.packages += 1
            for released in self.order.take(sender, package, time):
                self._decode(*released)

    def _decode(self, sender: str, package: bytes, time: float) -> None:
        """One package, in the order the session needs them: batched by recipe, or a control row."""
        if package[TYPE_AT] == DATA_PACKAGE_TYPE:
            package = self.session.guide_form(sender, package) or package  # protocol 1, without its id
        if package[TYPE_AT] == DATA_PACKAGE_TYPE and len(package) > RECIPE_ID_AT:
            codec = self._codec(sender, package)
            if codec is not None:
                self._batch(sender, package[RECIPE_ID_AT], codec, package, time)
                return
        self._control(sender, package, time)

    def _check(self, sender: str) -> Check:
        """A resynchronisation candidate that is a data package must be of a recipe this direction
        has (its id and size): then it is surely one; of no recipe it has, surely not."""
        direction = RTDE_DIRECTIONS[sender]

        def check(buf: bytearray, at: int, size: int) -> int:
            if buf[at + TYPE_AT] != DATA_PACKAGE_TYPE:
                return WEAK
            implied = implied_recipe_id(sender, self.session.state.version)
            if implied is not None:  # a package of the implied recipe sent without its id
                bare = self.session.recipes.get((direction, implied))
                if bare is not None and size == RTDE_HEADER + bare.size:
                    return STRONG
            if size <= RECIPE_ID_AT:
                return NO
            if at + RECIPE_ID_AT >= len(buf):  # its recipe id has not arrived yet
                return WEAK
            codec = self.session.recipes.get((direction, buf[at + RECIPE_ID_AT]))
            if codec is None and direction == "output":
                codec = self.given
            if codec is not None:
                return STRONG if codec.package_size == size else NO
            return NO if any(d == direction for d, _ in self.session.recipes) else WEAK

        return check

    def framings(self) -> dict[str, Framing]:
        return self.framing

    def finish(self) -> None:
        """The end of the capture: packages held back for confirmation are decoded."""
        for sender, framing in self.framing.items():
            self._packages(sender, framing.finish(), framing.times, self.last_time)
        for released in self.order.finish():
            self._decode(*released)

    def run_codec(self, sender: str, package: bytes) -> RecipeCodec | None:
        """The codec for a run of whole data packages like `package`, one per segment, from here on.

        Only when nothing is held in the framing (the run starts on a package boundary) nor waits
        for the other direction (the run goes behind what waits).
        """
        framing = self.framing[sender]
        if framing.buf or not framing.synced or self.order.holds(sender):
            return None
        return self._codec(sender, package)

    def feed_run(self, sender: str, codec: RecipeCodec, rows: Any, times: Any) -> None:
        """Whole data packages of `codec` (numpy uint8 rows, one package each), each from its
        own segment at `times`; decoded straight from the rows, which may be a view of the file."""
        key = (sender, int(rows[0, RECIPE_ID_AT]))
        self._flush(key)  # rows batched before the run come first
        self.counts.packages += len(times)
        self.batches[key] = (codec, rows, times)
        self._flush(key)

    def name_table(self, sender: str, codec: RecipeCodec) -> None:
        """The recipe's table named where its first package is, not where its rows are written
        (runs are written at once, batches wait, runs held for more wait too): rtde_outputs_1 is
        the first recipe met, however the packages were read."""
        self.sink.table_for_recipe(RTDE_DIRECTIONS[sender], codec.names)

    def _codec(self, sender: str, package: bytes) -> RecipeCodec | None:
        direction = RTDE_DIRECTIONS[sender]
        codec = self.session.recipes.get((direction, package[3]))
        if codec is None and direction == "output" and self.given is not None:
            codec = self.given
        if codec is None or codec.package_size != len(package):
            return None  # the generic path decodes it, or says why not
        return codec

    def _batch(self, sender: str, recipe_id: int, codec: RecipeCodec, package: bytes, time: float) -> None:
        key = (sender, recipe_id)
        if key not in self.batches or self.batches[key][0] is not codec:
            self._flush(key)
            self.name_table(sender, codec)
            self.batches[key] = (codec, [], [])
        _, raws, times = self.batches[key]
        raws.append(package)
        times.append(time)
        if len(raws) >= BATCH:
            self._flush(key)

    def _flush(self, key: tuple[str, int]) -> None:
        entry = self.batches.pop(key, None)
        if entry is None or not len(entry[1]):
            return
        import numpy as np

        codec, raws, times = entry
        array = codec.decode_many(raws if isinstance(raws, np.ndarray) else b"".join(raws))
        rows = len(array)
        table = self.sink.table_for_recipe(RTDE_DIRECTIONS[key[0]], codec.names)
        columns: dict[str, Any] = {
            "connection": np.full(rows, self.name),
            "capture_time": np.array(times),
        }
        columns.update({name: array[name] for name in codec.names})
        self.sink.columns(table, self.robot, day_of(times[0]), columns)

    def _control(self, sender: str, package: bytes, time: float) -> None:
        for key in list(self.batches):
            self._flush(key)  # keep the order of tables' rows with the setup exchange
        try:
            decoded = self.session.feed(sender, package)  # type: ignore[arg-type]
        except RtdeSpecError as exc:
            self.counts.errors.append(f"{sender} package at {time:.6f}: {exc}")
            return
        message = decoded.package
        base = {"connection": self.name, "capture_time": time, "sender": sender}
        if message.name in TEXTS:
            fields = message.values
            row = {**base, "level": fields.get("warning_level", fields.get("message_type")),
                   "source": fields.get("source", ""), "message": fields["message"]}  # fmt: skip
            self.sink.row("rtde_text", self.robot, day_of(time), row)
        elif message.name == DATA:
            if decoded.values is not None:
                direction = RTDE_DIRECTIONS[sender]
                names = tuple(decoded.values)
                table = self.sink.table_for_recipe(direction, names)
                codec = self.session.recipes.get((direction, package[RECIPE_ID_AT]))
                values = wide_values(decoded.values, codec)
                self.sink.row(table, self.robot, day_of(time), {**base, **values})
            elif self.given is None or RTDE_DIRECTIONS[sender] != "output":
                sizes = self.counts.unknown_recipe_sizes
                sizes[len(package)] = sizes.get(len(package), 0) + 1
            else:
                self.counts.errors.append(
                    f"{sender} data package at {time:.6f}: not of the given recipe ({len(package)} bytes; "
                    f"the recipe's packages are {self.given.package_size}): check --recipe"
                )
        else:
            fields_json = json.dumps(plain(message.values))
            row = {**base, "package": message.name, "fields": fields_json, "note": decoded.note or ""}
            self.sink.row("rtde_setup", self.robot, day_of(time), row)
            if decoded.problem:
                self.counts.errors.append(f"{sender} {message.name} at {time:.6f}: {decoded.problem}")

    def close(self) -> None:
        for released in self.order.finish():  # stopped early (Ctrl-C): what waits reaches the tables too
            self._decode(*released)
        for key in list(self.batches):
            self._flush(key)
