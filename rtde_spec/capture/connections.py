"""One TCP connection of a capture: its protocol, its two directions, and its decoded packages.

RTDE connections keep the session state (protocol version, recipes from the setup
exchange) through `SessionDecoder`; data packages of a known recipe are batched and
decoded together. After a gap the stream is searched for the next package boundary
that two consecutive headers confirm. Primary/secondary connections decode the
controller's messages; what the client sends is URScript.
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel

from rtde_spec._generated import rtde_models as gen
from rtde_spec._generated.constants import (
    DATA_PACKAGE_PREFIX_OFFSETS,
    DATA_PACKAGE_TYPE,
    RTDE_DIRECTIONS,
    RTDE_HEADER_FORMAT,
    RTDE_LIMITS,
)
from rtde_spec.capture.sink import TableSink, day_of
from rtde_spec.capture.tcp import Chunk
from rtde_spec.errors import RtdeSpecError
from rtde_spec.output.base import plain
from rtde_spec.primary.base import PrimaryPart, RobotStateMessage
from rtde_spec.primary.codec import default_codec
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.session import SessionDecoder
from rtde_spec.spec.catalogue import Catalogue

BATCH = 4096
RTDE_HEADER = struct.calcsize(RTDE_HEADER_FORMAT)
_SIZE_AT, _TYPE_AT, RECIPE_ID_AT = DATA_PACKAGE_PREFIX_OFFSETS
RTDE_SIZE_BYTES = _TYPE_AT - _SIZE_AT  # the size field leads the header


@dataclass
class Counts:
    packages: int = 0
    errors: list[str] = field(default_factory=list)
    unknown_recipe_sizes: dict[int, int] = field(default_factory=dict)  # data package size -> count


class Framing:
    """Cut one direction's bytes into packages; after a gap, find a boundary two headers confirm."""

    def __init__(self, size_bytes: int, header: int, types: set[int], max_size: int) -> None:
        self.size_bytes, self.header, self.types, self.max_size = size_bytes, header, types, max_size
        self.buf = bytearray()
        self.synced = True

    def plausible(self, at: int) -> int | None:
        buf = self.buf
        if len(buf) - at < self.header:
            return None
        size = int.from_bytes(buf[at : at + self.size_bytes], "big")
        if size < self.header or size > self.max_size or buf[at + self.size_bytes] not in self.types:
            return None
        return size

    def feed(self, chunk: Chunk) -> list[bytes]:
        if chunk.gap_before:
            self.buf.clear()
            self.synced = False
        self.buf += chunk.data
        if not self.synced and not self._resync():
            return []
        out: list[bytes] = []
        pos = 0
        buf = self.buf
        while len(buf) - pos >= self.header:
            size = self.plausible(pos)
            if size is None:  # not a header where one must be: treat as lost sync
                del buf[:pos]
                self.synced = False
                if not self._resync():
                    return out
                pos = 0
                continue
            if len(buf) - pos < size:
                break
            out.append(bytes(buf[pos : pos + size]))
            pos += size
        del buf[:pos]
        return out

    def _resync(self) -> bool:
        for at in range(len(self.buf) - self.header + 1):
            size = self.plausible(at)
            if size is None:
                continue
            following = at + size
            if following == len(self.buf) or self.plausible(following) is not None:
                del self.buf[:at]
                self.synced = True
                return True
        keep = self.header - 1
        if len(self.buf) > keep:
            del self.buf[: len(self.buf) - keep]
        return False


class RtdeConnection:
    def __init__(
        self, name: str, robot: str, sink: TableSink, given: RecipeCodec | None, catalogue: Catalogue
    ) -> None:
        self.name, self.robot, self.sink, self.given = name, robot, sink, given
        self.session = SessionDecoder(catalogue=catalogue)
        types = set(gen.PACKAGE_TYPES)
        limit = RTDE_LIMITS["package_max_bytes"]
        self.framing = {
            s: Framing(RTDE_SIZE_BYTES, RTDE_HEADER, types, limit) for s in ("controller", "client")
        }
        self.counts = Counts()
        self.batches: dict[tuple[str, int], tuple[RecipeCodec, Any, Any]] = {}  # packages: bytes list or rows

    def feed(self, sender: str, chunk: Chunk) -> None:
        for package in self.framing[sender].feed(chunk):
            self.counts.packages += 1
            if package[2] == DATA_PACKAGE_TYPE and len(package) > 3:
                codec = self._codec(sender, package)
                if codec is not None:
                    self._batch(sender, package[3], codec, package, chunk.time)
                    continue
            self._control(sender, package, chunk.time)

    def run_codec(self, sender: str, package: bytes) -> RecipeCodec | None:
        """The codec for a run of whole data packages like `package`, one per segment, from here on.

        Only when nothing is held in the framing (the run starts on a package boundary).
        """
        framing = self.framing[sender]
        if framing.buf or not framing.synced:
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
        message = decoded.message
        base = {"connection": self.name, "capture_time": time, "sender": sender}
        if isinstance(message, (gen.TextMessage, gen.TextMessageV1Controller, gen.TextMessageV1Client)):
            fields = message.fields()
            row = {**base, "level": fields.get("warning_level", fields.get("message_type")),
                   "source": fields.get("source", ""), "message": fields["message"]}  # fmt: skip
            self.sink.row("rtde_text", self.robot, day_of(time), row)
        elif isinstance(message, gen.DataPackage):
            if decoded.values is not None:
                direction = RTDE_DIRECTIONS[sender]
                names = tuple(decoded.values)
                table = self.sink.table_for_recipe(direction, names)
                self.sink.row(table, self.robot, day_of(time), {**base, **decoded.values})
            elif self.given is None or RTDE_DIRECTIONS[sender] != "output":
                sizes = self.counts.unknown_recipe_sizes
                sizes[len(package)] = sizes.get(len(package), 0) + 1
            else:
                self.counts.errors.append(f"{sender} data package at {time:.6f}: not of the given recipe")
        else:
            fields_json = json.dumps(plain(message.fields()))
            row = {**base, "package": message.NAME, "fields": fields_json, "note": decoded.note or ""}
            self.sink.row("rtde_setup", self.robot, day_of(time), row)

    def close(self) -> None:
        for key in list(self.batches):
            self._flush(key)


class PrimaryConnection:
    def __init__(self, name: str, robot: str, sink: TableSink) -> None:
        self.name, self.robot, self.sink = name, robot, sink
        self.codec = default_codec()
        families = {f.spec.type for f in self.codec.families.values()}
        codec = self.codec
        self.framing = Framing(codec.size_bytes, codec.header.size, families, codec.max_size)
        self.counts = Counts()

    def feed(self, sender: str, chunk: Chunk) -> None:
        base = {"connection": self.name, "capture_time": chunk.time}
        day = day_of(chunk.time)
        if sender == "client":  # URScript (or anything else a client sends)
            text = chunk.data.decode("utf-8", "replace")
            self.sink.row("primary_scripts", self.robot, day, {**base, "script": text})
            return
        for raw in self.framing.feed(chunk):
            self.counts.packages += 1
            try:
                message = self.codec.decode_message(raw)
            except RtdeSpecError as exc:
                self.counts.errors.append(f"message at {chunk.time:.6f}: {exc}")
                continue
            parts = message.sub_packages if isinstance(message, RobotStateMessage) else [message]
            for part in parts:
                name = getattr(part, "NAME", "unknown")
                values = (
                    flatten_part(part)
                    if isinstance(part, PrimaryPart)
                    else {"raw": bytes(getattr(part, "raw", b"")).hex()}
                )
                self.sink.row(f"primary_{name}", self.robot, day, {**base, **values})

    def close(self) -> None:
        pass


def flatten_part(part: PrimaryPart) -> dict[str, Any]:
    """A sub-package or message as one flat row: groups and vectors spread into numbered columns."""
    out: dict[str, Any] = {}

    def put(prefix: str, value: Any) -> None:
        if isinstance(value, BaseModel):
            for key in type(value).model_fields:
                put(f"{prefix}_{key}", getattr(value, key))
        elif isinstance(value, (list, tuple)) and value and not isinstance(value[0], (str, dict)):
            for i, item in enumerate(value):
                put(f"{prefix}_{i}", item)
        elif isinstance(value, (list, tuple, dict)):
            out[prefix] = json.dumps(plain(value))
        elif isinstance(value, (bytes, bytearray)):
            out[prefix] = bytes(value).hex()
        else:
            out[prefix] = value

    for key, value in part.values().items():
        put(key, value)
    return out
