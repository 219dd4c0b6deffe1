"""Time plots of table columns: one panel per field, one line per vector component, units from the spec."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rtde_spec.errors import UsageError, require
from rtde_spec.output.partfile import write_with


def components(columns: Mapping[str, Any], field: str) -> list[str]:
    """The column itself, or its name_0..name_N components in order."""
    if field in columns:
        return [field]
    found = [c for c in columns if c.startswith(f"{field}_") and c[len(field) + 1 :].isdigit()]
    return sorted(found, key=lambda c: int(c.rsplit("_", 1)[1]))


def plot_columns(
    columns: Mapping[str, Sequence[float]] | Mapping[str, Mapping[str, Sequence[float]]],
    fields: Sequence[str],
    time_column: str,
    path: str | Path,
    title: str | None = None,
) -> None:
    """Write a PNG; needs matplotlib (the `plot` extra).

    `columns` is one table's columns, or {label: columns} for several (e.g. one per
    robot of a dataset), drawn in the same panels with the label in the legend. The
    image appears only whole: drawn beside `path` and renamed into place (see `partfile`).
    """
    from rtde_spec.metamodel.catalogue import Catalogue

    matplotlib = require("matplotlib", "plot", "plotting")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tables: Mapping[str, Mapping[str, Sequence[float]]]
    if columns and all(isinstance(v, Mapping) for v in columns.values()):
        tables = columns  # type: ignore[assignment]
    else:
        tables = {"": columns}  # type: ignore[dict-item]
    cat = Catalogue.default()
    size = (9, 3.2 * len(fields) if len(fields) > 1 else 4.5)
    fig, axes = plt.subplots(len(fields), 1, figsize=size, sharex=True, squeeze=False)
    try:
        for ax, field in zip(axes[:, 0], fields, strict=True):
            lines = 0
            for label, table in tables.items():
                names = components(table, field)
                if not names:
                    raise UsageError(f"no column {field!r} (nor {field}_0, ...)")
                for name in names:
                    ax.plot(table[time_column], table[name], label=f"{label} {name}".strip())
                    lines += 1
            info = cat.get(field, "output") or cat.get(field, "input")
            unit = f" [{info.unit}]" if info is not None and info.unit else ""
            ax.set_ylabel(f"{field}{unit}")
            ax.grid(alpha=0.3)
            if lines > 1:
                ax.legend(ncol=3, fontsize="small")
        axes[-1, 0].set_xlabel(f"{time_column} [s]")
        if title:
            axes[0, 0].set_title(title)
        fig.tight_layout()
        target = Path(path)
        kind = target.suffix.lstrip(".").lower() or "png"
        # as every output: beside the name, renamed when whole, through a symlink, errors naming it
        write_with(target, lambda out: fig.savefig(out, dpi=100, format=kind))
    finally:
        plt.close(fig)
