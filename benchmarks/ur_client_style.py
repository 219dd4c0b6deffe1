"""Baselines written the way UR's official Python client (rtde/serialize.py) does the work.

Reproduced here, not imported: UR's client is not on the package registry. Type
codes are the baseline's own table, as UR's client keeps one; the package under
test takes them from the spec.
"""

from __future__ import annotations

import statistics
import struct
import time
from collections.abc import Callable
from typing import Any

SIZES = {"VECTOR6D": 6, "VECTOR3D": 3, "VECTOR6INT32": 6, "VECTOR6UINT32": 6}
CODES = {
    "VECTOR6D": "d" * 6,
    "VECTOR3D": "d" * 3,
    "VECTOR6INT32": "i" * 6,
    "VECTOR6UINT32": "I" * 6,
    "DOUBLE": "d",
    "UINT32": "I",
    "UINT64": "Q",
    "INT32": "i",
    "BOOL": "?",
    "UINT8": "B",
}


def baseline_decoder(names: list[str], types: list[str]) -> Callable[[bytes], dict]:
    """UR's client style: unpack the recipe, then convert field by field into a dict."""
    fmt = ">" + "".join(CODES[t] for t in types)

    def unpack_field(data: tuple, offset: int, data_type: str) -> object:
        size = SIZES.get(data_type, 1)
        if data_type in ("VECTOR6D", "VECTOR3D"):
            return [float(data[offset + i]) for i in range(size)]
        if data_type in ("VECTOR6UINT32", "VECTOR6INT32"):
            return [int(data[offset + i]) for i in range(size)]
        if data_type == "DOUBLE":
            return float(data[offset])
        if data_type in ("UINT32", "UINT8", "INT32", "UINT64"):
            return int(data[offset])
        if data_type == "BOOL":
            return bool(data[offset])
        raise ValueError(data_type)

    def decode(payload: bytes) -> dict:
        data = struct.unpack_from(fmt, payload)
        obj = {}
        offset = 0
        for name, data_type in zip(names, types, strict=True):
            obj[name] = unpack_field(data, offset, data_type)
            offset += SIZES.get(data_type, 1)
        return obj

    return decode


class DataObject:
    """UR's serialize.DataObject: values as attributes, packed in recipe order."""

    recipe_id: int | None = None

    def pack(self, names: list[str], types: list[str]) -> list[Any]:
        if len(names) != len(types):
            raise ValueError("List sizes are not identical.")
        out: list[Any] = []
        if self.recipe_id is not None:
            out.append(self.recipe_id)
        for name, data_type in zip(names, types, strict=True):
            value = self.__dict__[name]
            if value is None:
                raise ValueError("Uninitialized parameter: " + name)
            if data_type.startswith("VECTOR"):
                out.extend(value)
            else:
                out.append(value)
        return out


def baseline_encoder(names: list[str], types: list[str]) -> Callable[[DataObject], bytes]:
    """UR's client style send(): the recipe's format once, DataObject.pack, header + payload."""
    fmt = ">B" + "".join(CODES[t] for t in types)  # recipe id, then the variables

    def send(obj: DataObject) -> bytes:
        payload = struct.pack(fmt, *obj.pack(names, types))
        size = struct.calcsize(">HB") + len(payload)
        return struct.pack(">HB", size, 85) + payload

    return send


def per_call_ns(fn: Callable[[], object], calls: int, repeats: int = 7) -> float:
    """Median over repeats of the mean time per call, in nanoseconds."""
    samples = []
    for _ in range(repeats):
        start = time.perf_counter_ns()
        for _ in range(calls):
            fn()
        samples.append((time.perf_counter_ns() - start) / calls)
    return statistics.median(samples)
