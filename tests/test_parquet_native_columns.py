"""`native_columns` (Parquet's copy of a batch out of the packages, a block of rows at a time) gives
exactly what `flat_columns` gives: the same names in the same order, types and bytes."""

from __future__ import annotations

import numpy as np
import pytest

from rtde_spec import Catalogue, RecipeCodec
from rtde_spec.output.base import flat_columns
from rtde_spec.output.parquet import block_rows, native_columns

RECIPES = (
    ("timestamp",),
    ("actual_q",),
    ("robot_mode", "actual_q", "speed_scaling", "actual_digital_input_bits", "target_q", "runtime_state"),
    ("timestamp", "target_q", "target_qd", "actual_TCP_pose", "joint_mode", "safety_mode",
     "actual_main_voltage", "output_int_register_0", "output_double_register_0",
     "output_bit_registers0_to_31", "tool_mode"),
)  # fmt: skip


@pytest.mark.parametrize("names", RECIPES)
@pytest.mark.parametrize("blocks", [0, 1, "one less", "one", "one more", "three and some"])
def test_the_same_columns_as_flat_columns(names: tuple[str, ...], blocks: int | str) -> None:
    codec = RecipeCodec.for_names(list(names), "output", Catalogue.builtin())
    stride = codec.package_size + 70  # one package per row with capture headers between, as in a file
    block = block_rows(stride)  # rows on both sides of a block's end
    shift = {"one less": block - 1, "one": block, "one more": block + 1, "three and some": 3 * block + 7}
    rows = shift.get(blocks, blocks)  # type: ignore[call-overload]
    raw = np.random.default_rng(rows).integers(0, 256, size=stride * (rows + 1), dtype=np.uint8)
    packages = np.ndarray((rows,), dtype=codec.dtype, buffer=raw, strides=(stride,))
    columns = {"connection": np.full(rows, "10.0.0.2:51000"), "capture_time": np.arange(rows, dtype=float)}
    columns.update({name: packages[name] for name in codec.names})
    want, got = flat_columns(columns), native_columns(columns)
    assert list(got) == list(want)
    for name, column in want.items():
        assert got[name].dtype == column.dtype and got[name].shape == column.shape, name
        assert got[name].tobytes() == column.tobytes(), name


def test_columns_not_side_by_side_are_copied_on_their_own() -> None:
    """Two big-endian columns that are not neighbours in memory are not taken for one run."""
    a = np.arange(1000, dtype=">f8")
    b = np.arange(1000, 2000, dtype=">f8")
    vectors = np.arange(3000, dtype=">i4").reshape(1000, 3)[:, ::-1]  # elements not in order
    got = native_columns({"a": a, "b": b, "v": vectors})
    assert list(got) == ["a", "b", "v_0", "v_1", "v_2"]
    assert got["a"].tolist() == a.tolist() and got["b"].tolist() == b.tolist()
    assert got["v_0"].tolist() == vectors[:, 0].tolist() and got["a"].dtype.isnative
