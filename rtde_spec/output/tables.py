"""Bulk-decoded data packages as pandas DataFrames or Arrow tables (optional extras).

Vectors become one column per element (`actual_q_0` .. `actual_q_5`) in pandas,
and a fixed-size list column in Arrow; values are converted to native byte order.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rtde_spec.errors import UsageError, require

HEADER_COLUMNS = ("size", "type")


def _columns(arr: Any, keep_header: bool) -> dict[str, Any]:
    names = getattr(getattr(arr, "dtype", None), "names", None)
    if not names:  # a list, a dict, a plain array: an AttributeError or TypeError from inside
        raise UsageError(
            "to_pandas and to_arrow take the structured array RecipeCodec.decode_many returns, "
            f"not {type(arr).__name__}" + (f" of {arr.dtype}" if hasattr(arr, "dtype") else "")
        )
    out: dict[str, Any] = {}
    for name in names:
        if name in HEADER_COLUMNS and not keep_header:
            continue
        column = arr[name]
        out[name] = column.astype(column.dtype.newbyteorder("="))
    return out


def to_pandas(arr: Any, keep_header: bool = False) -> Any:
    """A DataFrame from `RecipeCodec.decode_many`; vectors split into name_0..name_n."""
    pd = require("pandas", "pandas", "to_pandas")
    flat: dict[str, Any] = {}
    for name, column in _columns(arr, keep_header).items():
        if column.ndim == 1:
            flat[name] = column
        else:
            for i in range(column.shape[1]):
                flat[f"{name}_{i}"] = column[:, i]
    return pd.DataFrame(flat)


def to_arrow(arr: Any, keep_header: bool = False) -> Any:
    """A pyarrow Table from `RecipeCodec.decode_many`; vectors as fixed-size lists."""
    require("pyarrow", "arrow", "to_arrow")
    import pyarrow as pa

    columns = {}
    for name, column in _columns(arr, keep_header).items():
        if column.ndim == 1:
            columns[name] = arrow_array(column)
        else:
            values = arrow_array(column.reshape(-1))
            columns[name] = pa.FixedSizeListArray.from_arrays(values, column.shape[1])
    return pa.Table.from_arrays(list(columns.values()), names=list(columns))


def arrow_array(column: Any) -> Any:
    """A 1-D numpy column (native byte order) as an Arrow array, without a copy where it can.

    Built from the column's buffer rather than with `pa.array`, which imports pandas
    to look for pandas types: 50 MB and a quarter second that a numpy column never needs.
    """
    import numpy as np
    import pyarrow as pa

    if column.dtype.kind == "U":  # text (connection names, robots, dates): offsets and UTF-8 bytes
        if len(column) and (column == column[0]).all():  # one value throughout (a connection's name)
            one = str(column[0]).encode("utf-8", "replace")  # a lone surrogate becomes '?', not an error
            offsets = np.arange(len(column) + 1, dtype=np.int32) * len(one)
            buffers = [None, pa.py_buffer(offsets), pa.py_buffer(one * len(column))]
            return pa.Array.from_buffers(pa.string(), len(column), buffers)
        return _strings([value.encode("utf-8", "replace") for value in column.tolist()])
    if column.dtype.kind not in "biuf":  # objects: pyarrow's own conversion
        return pa.array(column)
    if column.dtype.kind == "b":
        bits = np.packbits(column, bitorder="little")  # Arrow keeps bools as a bitmap
        return pa.Array.from_buffers(pa.bool_(), len(column), [None, pa.py_buffer(bits)])
    column = np.ascontiguousarray(column)
    return pa.Array.from_buffers(pa.from_numpy_dtype(column.dtype), len(column), [None, pa.py_buffer(column)])


def _strings(encoded: list[bytes], valid: Any = None) -> Any:
    """UTF-8 texts as an Arrow string array (`valid`: its validity bitmap, if any are null)."""
    import numpy as np
    import pyarrow as pa

    offsets = np.zeros(len(encoded) + 1, dtype=np.int32)
    np.cumsum([len(e) for e in encoded], out=offsets[1:])
    buffers = [valid, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))]
    return pa.Array.from_buffers(pa.string(), len(encoded), buffers)


def arrow_table(columns: Mapping[str, Any]) -> Any:
    """1-D native numpy columns as an Arrow table (see `arrow_array`).

    Fields without missing values are declared non-nullable: numpy columns have none,
    and Parquet then stores the column as REQUIRED, with no definition level per value
    (its encoding is about a quarter faster; every reader reads it).
    """
    import pyarrow as pa

    arrays = [arrow_array(c) for c in columns.values()]
    fields = [pa.field(n, a.type, nullable=a.null_count > 0) for n, a in zip(columns, arrays, strict=True)]
    return pa.Table.from_arrays(arrays, schema=pa.schema(fields))


def _column_of_values(values: list[Any]) -> Any:
    """One column of Python values as an Arrow array, nullable; numpy-built for the usual kinds
    (bool, int, float, str), so no pandas is imported; anything else by pyarrow's conversion."""
    import numpy as np
    import pyarrow as pa

    present = [v for v in values if v is not None]
    if not present:
        return pa.nulls(len(values))
    kinds = {type(v) for v in present}
    dtype: Any = None
    if kinds == {bool}:
        dtype = np.bool_
    elif kinds == {int}:
        low, high = min(present), max(present)
        if low >= 0 and (1 << 63) <= high < (1 << 64):
            dtype = np.uint64  # a UINT64 beyond int64 (bit fields, counters)
        elif -(1 << 63) <= low and high < (1 << 63):
            dtype = np.int64  # else beyond 64 bits: pyarrow's conversion says so
    elif kinds and kinds <= {int, float} and float in kinds:
        if any(type(v) is int and abs(v) > 1 << 53 for v in present):
            raise ValueError("integers too large for the floats beside them (kept exactly only to 2^53)")
        dtype = np.float64
    elif kinds == {str}:  # not through numpy, whose texts lose trailing NUL characters
        texts = [b"" if v is None else v.encode("utf-8", "replace") for v in values]
        return _strings(texts, None if len(present) == len(values) else _validity(values))
    elif (
        len(kinds) == 1
        and issubclass(kind := next(iter(kinds)), np.generic)
        and np.dtype(kind).kind in "biuf"
        and np.dtype(kind).itemsize <= 8  # not long double: Arrow has no such type
    ):
        dtype = kind  # numpy scalars of one type (a UINT64 of a primary message); pa.array imports pandas
    if dtype is None:
        if any(isinstance(v, np.generic) for v in present):  # numpy scalars mixed with others:
            plain = [v.item() if isinstance(v, np.generic) else v for v in values]  # as Python values
            if any(isinstance(v, np.generic) for v in plain):  # long double: no Python (nor Arrow) type
                raise TypeError(f"no Arrow type for numpy {type(present[0]).__name__}")
            return _column_of_values(plain)
        return pa.array(values)  # nested lists, bytes, mixed kinds: pyarrow's rules (and its errors)
    fill = False if dtype is np.bool_ else 0
    array = arrow_array(np.array([fill if v is None else v for v in values], dtype=dtype))
    if len(present) == len(values):
        return array
    return pa.Array.from_buffers(array.type, len(values), [_validity(values), *array.buffers()[1:]])


def _validity(values: list[Any]) -> Any:
    """Arrow's validity bitmap of a column of Python values: None is null."""
    import numpy as np
    import pyarrow as pa

    return pa.py_buffer(np.packbits(np.array([v is not None for v in values]), bitorder="little"))


def rows_table(rows: Sequence[Mapping[str, Any]], types: Mapping[str, str] | None = None) -> Any:
    """Row dicts as an Arrow table, as `pa.Table.from_pylist` makes it but for three things: every
    key of every row is a column (from_pylist keeps only the first row's keys: the rest were
    lost); a column of nulls only has the type `types` gives it (numpy codes, "str"; a file whose
    column is of Arrow's null type makes pandas, pyarrow and DuckDB refuse a folder whose other
    files hold values there); and no pandas is imported (a third of a second at every capture's
    start)."""
    import pyarrow as pa

    from rtde_spec.errors import EncodeError

    names = list(dict.fromkeys(key for row in rows for key in row))
    arrays = []
    for name in names:
        try:
            column = _column_of_values([row.get(name) for row in rows])
            if types and column.type == pa.null() and name in types:
                column = pa.nulls(len(column), arrow_type(types[name]))
            arrays.append(column)
        except (pa.ArrowException, OverflowError, ValueError, TypeError, UnicodeError) as exc:
            raise EncodeError(f"no table column can hold these values: {exc}", field=name) from None
    return pa.Table.from_arrays(arrays, names=names)


def arrow_type(kind: str) -> Any:
    """The Arrow type of a column kind: a numpy type code ("f8", "i8", "b1"; a trailing "?" marks
    it nullable and is ignored here) or "str"."""
    import pyarrow as pa

    code = kind.rstrip("?")
    return pa.string() if code == "str" else pa.from_numpy_dtype(code)
