"""Fleet scale with Dask (`pip install 'rtde_spec[dask]'`): capture files as a bag of tasks on a
cluster, the written dataset as a Dask DataFrame.

    bag = capture_bag(paths, "out/")             # one task per file, any scheduler or cluster
    summaries = bag.compute()
    frame = dataset_frame("out/", "rtde_outputs_1")   # hive-partitioned Parquet, lazily
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rtde_spec.capture.decoder import decode_to_directory
from rtde_spec.errors import require


def capture_bag(
    paths: Sequence[str | Path], outdir: str | Path, fmt: str = "parquet", recipe: Sequence[str] | None = None
) -> Any:
    """A dask.bag of CaptureSummary: each file decoded into OUTDIR by whichever worker takes it.

    A table name still holds one recipe (`tables/names.py`), but a recipe new to OUTDIR is
    numbered in the order the tasks finish: for names in input order, `rtde-spec capture --jobs N`."""
    bag = require("dask.bag", "dask", "capture_bag")
    names = list(recipe) if recipe else None
    return bag.from_sequence([str(p) for p in paths], npartitions=max(1, len(paths))).map(
        decode_to_directory, str(outdir), fmt, names
    )


def dataset_frame(outdir: str | Path, table: str) -> Any:
    """One table of the dataset as a dask.dataframe, partition columns (robot, date) included."""
    dd = require("dask.dataframe", "dask", "dataset_frame")
    return dd.read_parquet(str(Path(outdir) / table), dataset={"partitioning": "hive"})
