"""The numpy plan of a fixed layout: many records of the same `LayoutField`s decoded at once.

The per-record path (`layout.Layout`) unpacks one record into a dict; a capture of a
500 Hz stream wants columns. The dtype comes from the same fields and primitives (each
field its primitive's struct code in the layout's byte order, `count` as a sub-array),
and scaled fields are divided by their scale, so both paths give the same SI values.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rtde_spec.wire.fields import FieldLike, PrimitiveLike


def record_dtype(
    fields: Sequence[FieldLike], prims: Mapping[str, PrimitiveLike], order: str, itemsize: int
) -> Any:
    """A numpy structured dtype of fixed value fields, padded to `itemsize` bytes a record."""
    import numpy as np

    names, formats, offsets, at = [], [], [], 0
    for f in fields:
        prim = prims[f.type]
        base = np.dtype(order + prim.struct)
        names.append(f.name)
        formats.append((base, (f.count,)) if f.count else base)
        offsets.append(at)
        at += prim.size * (f.count or 1)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": itemsize})


def decode_columns(data: bytes, dtype: Any, fields: Sequence[FieldLike]) -> dict[str, Any]:
    """Columns (native order; 2-D for counted fields) of the records in `data`, scaled to SI."""
    import numpy as np

    records = np.frombuffer(data, dtype=dtype)
    out: dict[str, Any] = {}
    for f in fields:
        column = records[f.name]
        out[f.name] = (
            column / f.scale if f.scale is not None else column.astype(column.dtype.newbyteorder("="))
        )
    return out
