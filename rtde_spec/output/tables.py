"""Bulk-decoded data packages as pandas DataFrames or Arrow tables (optional extras).

Vectors become one column per element (`actual_q_0` .. `actual_q_5`) in pandas,
and a fixed-size list column in Arrow; values are converted to native byte order.
"""

from __future__ import annotations

from typing import Any

from rtde_spec.errors import require

HEADER_COLUMNS = ("size", "type")


def _columns(arr: Any, keep_header: bool) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for name in arr.dtype.names:
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
            columns[name] = pa.array(column)
        else:
            values = pa.array(column.reshape(-1))
            columns[name] = pa.FixedSizeListArray.from_arrays(values, column.shape[1])
    return pa.table(columns)
