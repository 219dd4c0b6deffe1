"""`native_columns` (Parquet's copy of a batch out of the packages, a block of rows at a time) gives
exactly what `flat_columns` gives: the same names in the same order, types and bytes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rtde_spec import Catalogue, RecipeCodec
from rtde_spec.output.base import flat_columns
from rtde_spec.output.native_columns import block_bytes, block_for, block_rows, level2_cache, native_columns

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


def _cache_dir(root: Path, caches: list[tuple[str, str, str]]) -> Path:
    for i, (level, kind, size) in enumerate(caches):
        index = root / f"index{i}"
        index.mkdir(parents=True)
        for name, text in (("level", level), ("type", kind), ("size", size)):
            (index / name).write_text(text + "\n")
    return root


@pytest.mark.parametrize(
    ("caches", "size", "block"),
    [
        ([("1", "Data", "32K"), ("1", "Instruction", "32K"), ("2", "Unified", "1024K"),
          ("3", "Unified", "32768K")], 1 << 20, 1 << 20),
        ([("1", "Data", "48K"), ("2", "Unified", "4M")], 4 << 20, 2 << 20),  # no more than 2 MB
        ([("1", "Data", "32K"), ("2", "Unified", "256K")], 256 << 10, 512 << 10),  # no less than 512 kB
        ([("1", "Data", "32K"), ("2", "Instruction", "2048K")], None, 1 << 20),  # no level-2 data cache
        ([("2", "Unified", "big")], None, 1 << 20),  # unreadable: the default
    ],
)  # fmt: skip
def test_blocks_are_as_large_as_the_level2_cache_within_bounds(
    tmp_path: Path, caches: list[tuple[str, str, str]], size: int | None, block: int
) -> None:
    """On a core with 1 MB of level-2 cache, 2 MB blocks took twice as long as 1 MB ones."""
    assert level2_cache(_cache_dir(tmp_path / "cache", caches)) == size
    assert block_for(size) == block


def test_a_machine_without_the_cache_in_sysfs_gets_the_default_block(tmp_path: Path) -> None:
    assert level2_cache(tmp_path / "missing") is None and block_for(None) == 1 << 20
    assert 512 << 10 <= block_bytes() <= 2 << 20  # this machine's, within the bounds
