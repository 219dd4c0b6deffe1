"""Rows and columns as timestamped JSON messages on topics: what MCAP files and the live view carry.

Topics: a recipe's data packages on `/rtde/outputs/<recipe id>` (or `/rtde/inputs/...`;
when rows carry no recipe id, the recipe's order of appearance, from 1), other RTDE
packages on `/rtde/<package>`, primary/secondary messages on `/primary/<message>`
with each Robot State sub-package on its own topic (`/primary/joint_data`, ...).
One JSON Schema per topic, generated from the spec (`json_schemas`).

Log times (nanoseconds since 1970, as MCAP and Foxglove take them):
- a capture's rows carry `capture_time`: the packet's time, as it is;
- otherwise the controller's `timestamp` (seconds since it started, or its µs in
  primary messages, as the spec's unit says) plus one offset per file, chosen so
  the first timestamped message is logged at the moment it was written: a
  recording's times are the wall clock's, with the controller's spacing exactly;
  `epoch` fixes the offset instead (0: the controller's own clock, since 1970);
- a message without either takes the last time logged (or the time of writing).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

from rtde_spec._generated.constants import DATA_PACKAGE_TYPE
from rtde_spec._generated.spec_data import SPEC
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.output import json_schemas as js
from rtde_spec.output.base import plain

CAPTURE_TIME = "capture_time"
LAST_NS_SECOND = 9.2e9  # seconds past which nanoseconds leave int64 (the year 2261): no log time
TIMESTAMP = "timestamp"
_SCALE = {"s": 1.0, "ms": 1e-3, "µs": 1e-6, "us": 1e-6, "ns": 1e-9}
_DATA_PACKAGE = next(m["name"] for m in SPEC["packages"]["messages"] if m["type"] == chr(DATA_PACKAGE_TYPE))


@dataclass(frozen=True)
class Message:
    """One message: its topic, the topic's schema (title = schema name), JSON data, log time in ns."""

    topic: str
    schema: dict[str, Any]
    data: bytes
    log_time: int


class Clock:
    """Log times in ns from capture times or controller timestamps; see the module's docstring."""

    def __init__(self, epoch: float | None = None) -> None:
        self.epoch_ns: int | None = None if epoch is None else round(epoch * 1e9)
        self.last: int | None = None

    def _keep(self, ns: int) -> int:
        self.last = max(ns, 0)
        return self.last

    def capture(self, seconds: float) -> int:
        ok = _finite(seconds) and abs(seconds) < LAST_NS_SECOND
        return self._keep(nanoseconds(seconds)) if ok else self.unknown()

    def controller(self, seconds: float) -> int:
        if not _finite(seconds):
            return self.unknown()
        if self.epoch_ns is None:
            self.epoch_ns = time.time_ns() - round(seconds * 1e9)
        return self._keep(self.epoch_ns + round(seconds * 1e9))

    def unknown(self) -> int:
        return self.last if self.last is not None else self._keep(time.time_ns())

    def many(self, columns: Mapping[str, Any], scale: float) -> Any:
        """Log times of a batch of rows (numpy int64), from its capture or controller time column."""
        import numpy as np

        rows = len(next(iter(columns.values())))
        if CAPTURE_TIME in columns:
            seconds, base = np.asarray(columns[CAPTURE_TIME], dtype=np.float64), 0
        elif TIMESTAMP in columns:
            seconds = np.asarray(columns[TIMESTAMP], dtype=np.float64) * scale
            good = np.isfinite(seconds)
            if self.epoch_ns is None and good.any():
                self.epoch_ns = time.time_ns() - round(float(seconds[good][0]) * 1e9)
            base = self.epoch_ns or 0
        else:
            return np.full(rows, self.unknown(), dtype=np.int64)
        ok = np.isfinite(seconds) & (np.abs(seconds) < LAST_NS_SECOND)
        # whole nanoseconds first, then the offset in integers: a float holds only ~0.25 µs at 1e18;
        # whole seconds and the fraction apart, so a log time is the time the float holds to the
        # nanosecond (seconds * 1e9 rounded to 256 ns at today's epoch: up to 128 ns more error)
        kept = np.where(ok, seconds, 0)
        whole = np.floor(kept)
        out = whole.astype(np.int64) * np.int64(10**9) + ((kept - whole) * 1e9).round().astype(np.int64)
        out = (out + np.int64(base)).clip(0)
        if not ok.all():  # a row without a time takes the one before it
            last = self.unknown() if self.last is None else self.last
            for i in np.flatnonzero(~ok):
                out[i] = out[i - 1] if i else last
        if rows:
            self.last = int(out[-1])
        return out


def nanoseconds(seconds: float) -> int:
    """The nanosecond nearest the time a float of seconds holds: whole seconds and the fraction
    apart (the fraction is exact), since `seconds * 1e9` is rounded to a multiple of 256 ns past
    2**60 ns (a capture time since 1970)."""
    whole = math.floor(seconds)
    return whole * 10**9 + round((seconds - whole) * 1e9)


def topic_for_table(table: str) -> str:
    """The topic of a capture table, named as `decode` names it: rtde_outputs_1 -> /rtde/outputs/1,
    primary_joint_data -> /primary/joint_data, rtde_setup -> /rtde/setup."""
    interface, _, rest = table.partition("_")
    kind, _, number = rest.rpartition("_")
    if interface == "rtde" and kind in ("inputs", "outputs") and number.isdigit():
        return f"/rtde/{kind}/{number}"
    return f"/{interface}/{rest}" if rest else f"/{table}"


def _finite(value: Any) -> bool:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int beyond any double
        return False


def _dumps() -> Any:
    try:
        import orjson

        return orjson.dumps
    except ImportError:
        return lambda value: json.dumps(js.finite(value), separators=(",", ":")).encode()


class Topics:
    """Splits rows and columnar batches into messages on topics, one schema per topic.

    `topic`: every row on this one topic (a capture table's own file); None: by content.
    `protocol`: "rtde" or "primary" for rows of packages; None: RTDE if a row names its
    package type letter (as `decode` writes RTDE packages), else primary.
    """

    def __init__(
        self, topic: str | None = None, epoch: float | None = None, protocol: str | None = None
    ) -> None:
        self.topic = topic
        self.protocol = protocol
        self.clock = Clock(epoch)
        self.schemas: dict[str, dict[str, Any]] = {}
        self._catalogue = Catalogue.default()
        self._recipes: dict[tuple[str, tuple[str, ...]], int] = {}
        self._dumps = _dumps()
        self._lines: Any = None

    # --- rows -----------------------------------------------------------------

    def messages(self, record: Mapping[str, Any]) -> list[Message]:
        """The messages of one row: one, or one per Robot State sub-package."""
        row = plain(record)
        subs = row.get("sub_packages")
        if isinstance(subs, list) and self.topic is None:
            return self._robot_state(row, subs)
        topic, known = self._route(row)
        when = self._row_time(row, known)
        return [self._message(topic, row, known, when if when is not None else self.clock.unknown())]

    def _robot_state(self, row: Mapping[str, Any], subs: list[Any]) -> list[Message]:
        """Each sub-package on its own topic, all at the message's time (robot_mode_data's timestamp)."""
        parts = []
        for sub in subs:
            sub = sub if isinstance(sub, dict) else {"value": sub}
            name = str(sub.get("package", "unknown"))
            lead = {"offset": row["offset"]} if "offset" in row else {}
            body = {**lead, **{k: v for k, v in sub.items() if k != "package"}}
            parts.append((name, body, js.primary_part(name)))
        when = self._row_time(row, None)
        for _, body, known in parts:
            when = when if when is not None else self._row_time(body, known)
        when = when if when is not None else self.clock.unknown()
        return [self._message(f"/primary/{name}", body, known, when) for name, body, known in parts]

    def _route(self, row: Mapping[str, Any]) -> tuple[str, dict[str, dict[str, Any]]]:
        package = row.get("package")
        if self.topic is not None:
            name = str(package) if package else self.topic.rpartition("/")[2]  # a capture table's part
            known = {**js.rtde_package(name), **js.primary_part(name)}
            return self.topic, {**known, **js.recipe_fields(list(row), self._catalogue)}
        if package is None or (package == _DATA_PACKAGE and self._recipe_names(row)):
            names = self._recipe_names(row)
            return self._recipe_topic(names, row.get("recipe_id")), js.recipe_fields(names, self._catalogue)
        # a name both interfaces use (text_message): RTDE rows name their type letter
        shared = package in js.primary_part_names()
        rtde = self.protocol == "rtde" or (self.protocol is None and ("package_type" in row or not shared))
        if rtde and package in js.rtde_package_names():
            return f"/rtde/{package}", js.rtde_package(str(package))
        return f"/primary/{package}", js.primary_part(str(package))

    def _recipe_names(self, row: Mapping[str, Any]) -> tuple[str, ...]:
        cat = self._catalogue
        return tuple(n for n in row if cat.get(n, "output") or cat.get(n, "input"))

    def _recipe_topic(self, names: tuple[str, ...], recipe_id: Any) -> str:
        cat = self._catalogue
        direction = "output" if any(cat.get(n, "output") for n in names) else "input"
        if recipe_id is None:
            key = (direction, names)
            if key not in self._recipes:
                self._recipes[key] = 1 + sum(1 for d, _ in self._recipes if d == direction)
            recipe_id = self._recipes[key]
        return f"/rtde/{direction}s/{int(recipe_id)}"

    def _row_time(self, row: Mapping[str, Any], known: Mapping[str, dict[str, Any]] | None) -> int | None:
        if CAPTURE_TIME in row and _finite(row[CAPTURE_TIME]):
            return self.clock.capture(float(row[CAPTURE_TIME]))
        if TIMESTAMP in row and _finite(row[TIMESTAMP]):
            return self.clock.controller(float(row[TIMESTAMP]) * self._scale(known))
        return None

    def _scale(self, known: Mapping[str, dict[str, Any]] | None) -> float:
        """Seconds per unit of the `timestamp` field the spec describes (RTDE: s; primary: µs)."""
        text = str((known or {}).get(TIMESTAMP, {}).get("description", ""))
        unit = text.rpartition("[")[2].rstrip("]") if text.endswith("]") else "s"
        return _SCALE.get(unit, 1.0)

    def _message(self, topic: str, body: Mapping[str, Any], known: Mapping[str, Any], when: int) -> Message:
        schema = self.schemas.get(topic)
        if schema is None:
            schema = self.schemas[topic] = js.object_schema(topic.strip("/").replace("/", "."), body, known)
        return Message(topic, schema, self._dumps(body), when)

    # --- columns --------------------------------------------------------------

    def column_messages(
        self, columns: Mapping[str, Any]
    ) -> Iterator[tuple[str, dict[str, Any], list[bytes], Any]]:
        """A batch of data packages: (topic, schema, JSON of each row, log times) per recipe id."""
        import numpy as np

        if not columns:
            return
        ids = columns.get("recipe_id")
        if ids is not None and len(ids) and self.topic is None and (ids != ids[0]).any():
            for rid in np.unique(ids):  # rows of several recipes: each on its own topic
                pick = ids == rid
                yield from self.column_messages({k: v[pick] for k, v in columns.items()})
            return
        names = self._recipe_names(columns)
        known = js.recipe_fields(names, self._catalogue)
        if self.topic is not None:
            topic = self.topic
        else:
            topic = self._recipe_topic(names, int(ids[0]) if ids is not None and len(ids) else None)
        lines = self._json_rows(columns)
        if not lines:
            return
        if topic not in self.schemas:
            first = json.loads(lines[0])
            self.schemas[topic] = js.object_schema(topic.strip("/").replace("/", "."), first, known)
        times = self.clock.many(columns, self._scale(known))
        yield topic, self.schemas[topic], lines, times

    def _json_rows(self, columns: Mapping[str, Any]) -> list[bytes]:
        from rtde_spec.output import jsonlines
        from rtde_spec.output.base import native_order

        if jsonlines.fits(columns):
            if self._lines is None:
                self._lines = jsonlines.formatter()
            return self._lines(columns).split(b"\n")[:-1]  # type: ignore[no-any-return]
        names = list(columns)
        lists = [native_order(columns[n]).tolist() for n in names]
        return [self._dumps(plain(dict(zip(names, row, strict=True)))) for row in zip(*lists, strict=True)]
