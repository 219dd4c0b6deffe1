"""Row dicts to Arrow without pandas: the columns pyarrow's own conversion makes, every key kept."""

from __future__ import annotations

import subprocess
import sys
from typing import Any

import pyarrow as pa
from hypothesis import given, settings
from hypothesis import strategies as st

from rtde_spec.output.tables import rows_table
from tests.budget import examples

KEYS = ["a", "b", "c", "d"]
VALUES = {
    "a": st.none() | st.integers(-(2**63), 2**63 - 1),
    "b": st.none() | st.text(alphabet=st.characters(exclude_categories=["Cs"]), max_size=8),
    "c": st.none() | st.booleans(),
    "d": st.none() | st.floats(allow_nan=False) | st.integers(-1000, 1000),
}
ROW = st.fixed_dictionaries({}, optional={k: VALUES[k] for k in KEYS})


@settings(max_examples=examples(200), deadline=None)
@given(st.lists(ROW, min_size=1, max_size=12))
def test_rows_become_the_table_from_pylist_makes(rows: list[dict[str, Any]]) -> None:
    names = list(dict.fromkeys(k for row in rows for k in row))  # every row's keys, in order
    got = rows_table(rows)
    want = pa.table({n: pa.array([row.get(n) for row in rows]) for n in names})
    got.validate(full=True)
    assert got.column_names == want.column_names
    assert got.to_pylist() == want.to_pylist()
    for name in got.column_names:
        if want.column(name).null_count < len(want):  # a column of nulls only: any type will do
            assert got.schema.field(name).type == want.schema.field(name).type, name


def test_a_key_the_first_row_lacks_is_kept() -> None:
    rows = [{"a": 1}, {"a": 2, "later": "x"}]
    assert pa.Table.from_pylist(rows).column_names == ["a"]  # why rows_table exists
    assert rows_table(rows).column("later").to_pylist() == [None, "x"]


def test_uint64_beyond_int64_and_lone_surrogates_are_kept() -> None:
    table = rows_table([{"bits": 2**63 + 5, "text": "ok"}, {"bits": 7, "text": "\udcff"}])
    assert table.schema.field("bits").type == pa.uint64()
    assert table.column("bits").to_pylist() == [2**63 + 5, 7]
    assert table.column("text").to_pylist()[1] == "?"  # replaced, not an error


def test_making_a_table_of_rows_imports_no_pandas() -> None:
    code = (
        "import sys; from rtde_spec.output.tables import rows_table; "
        "rows_table([{'a': 1, 'b': 'x', 'c': True, 'd': None}]); print('pandas' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_texts_keep_trailing_nul_characters_and_nulls() -> None:
    """numpy's text arrays drop trailing NULs ('a\\x00' -> 'a'): texts do not go through them."""
    table = rows_table([{"t": "a\x00"}, {"t": None}, {"t": "\x00"}, {"u": 1}])
    assert table.column("t").to_pylist() == ["a\x00", None, "\x00", None]
    table.validate(full=True)


def test_numpy_scalars_keep_their_type_without_pandas() -> None:
    """A primary message's UINT64 arrives as a numpy scalar; pyarrow would import pandas for it."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np; from rtde_spec.output.tables import rows_table; "
        "t = rows_table([{'v': np.uint64(2**64 - 1)}, {'v': None}, {'v': np.uint64(3)}]); "
        "assert str(t.schema.field('v').type) == 'uint64', t.schema; "
        "assert t.column('v').to_pylist() == [2**64 - 1, None, 3]; "
        "assert 'pandas' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
