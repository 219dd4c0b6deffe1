"""Which table of an output folder holds which recipe: one name, one recipe, whatever the run.

Tables of data packages are numbered per recipe: rtde_outputs_1, rtde_outputs_2, ...,
rtde_inputs_1, ... A table's files are one dataset, so every file of it must have the same
columns: a name given to one recipe is never given to another in the same folder, by this
run or a later one. Each capture's listing, OUTDIR/recipes-<capture>.json, says which recipe
each of its tables holds; together the listings are the folder's register. A recipe gets the
table the register holds it in, else the lowest number no listing uses, in the order the
capture meets its recipes. Captures are put in place one at a time, in input order (`capture
--jobs N` decodes in parallel but places in order), each after checking its names against
the register under the folder's lock: the names depend on the inputs and the folder, never on
N or on which file is decoded first. The files of a capture whose names were taken meanwhile
move to the right ones (MCAP files, which name their table inside, are decoded again:
`PreparedTables.place` says so); nothing is put in place under a name that holds another recipe.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from rtde_spec.errors import OutputError

Recipe = tuple[str, tuple[str, ...]]  # (direction, field names in order): the columns of a table
LISTING_PREFIX, LISTING_SUFFIX = "recipes-", ".json"
_CACHE_MAX = 1 << 16
_listings: dict[str, tuple[tuple[int, int, int], list[tuple[str, Recipe]]]] = {}  # path -> (stat, entries)


def listing_name(stem: str) -> str:
    """The file listing the recipe tables of the capture whose outputs are named `stem`."""
    return f"{LISTING_PREFIX}{stem}{LISTING_SUFFIX}"


def recipe_table(direction: str, number: int) -> str:
    return f"rtde_{direction}s_{number}"


class TableNameError(OutputError):
    """The folder cannot give a recipe one table of its own (its tables already mix recipes)."""


@dataclass
class Register:
    """The recipe of every table named by the listings of one output folder."""

    outdir: Path
    holders: dict[str, dict[Recipe, list[str]]] = field(default_factory=dict)  # table -> recipe -> listings

    @classmethod
    def read(cls, outdir: str | Path) -> Register:
        """The folder's listings as they are now (none: a folder not made yet)."""
        outdir = Path(outdir)
        register = cls(outdir)
        try:
            names = sorted(os.listdir(outdir))
        except (FileNotFoundError, NotADirectoryError):
            return register
        except OSError as exc:
            raise OutputError(
                f"cannot list it ({exc.strerror or exc}): its listings say which recipe each table holds",
                errno=exc.errno,
                subject=f"folder {outdir}",
            ) from exc
        for name in names:
            if name.startswith(LISTING_PREFIX) and name.endswith(LISTING_SUFFIX):
                for table, recipe in listing_entries(outdir / name):
                    register.holders.setdefault(table, {}).setdefault(recipe, []).append(name)
        return register

    def tables_of(self, listing: str) -> set[str]:
        """The tables one listing names (a capture's outputs of an earlier run)."""
        return {t for t, recipes in self.holders.items() if any(listing in ls for ls in recipes.values())}

    def table_for(self, recipe: Recipe, assigned: Mapping[Recipe, str]) -> str:
        """The table of `recipe`: the one the folder holds it in, else the lowest free number
        (`assigned`: the names given so far to the capture's other recipes)."""
        if recipe in assigned:
            return assigned[recipe]
        held = sorted(t for t, recipes in self.holders.items() if recipe in recipes)
        for table in held:
            if len(self.holders[table]) > 1:
                raise self._mixed(table)
        if held:
            return held[0]
        used = set(self.holders) | set(assigned.values())
        number = 1
        while recipe_table(recipe[0], number) in used:
            number += 1
        return recipe_table(recipe[0], number)

    def assign(self, recipes: Sequence[Recipe]) -> dict[Recipe, str]:
        """The tables of a capture's recipes, in the order it met them."""
        out: dict[Recipe, str] = {}
        for recipe in recipes:
            out[recipe] = self.table_for(recipe, out)
        return out

    def _mixed(self, table: str) -> TableNameError:
        """A table that listings of earlier runs give to different recipes (an rtde-spec that
        numbered tables per capture wrote them): adding rows would mix it further."""
        held = self.holders[table]
        which = " and ".join(
            f"{', '.join(listings)} ({len(recipe[1])} fields: {', '.join(recipe[1][:3])}"
            f"{', ...' if len(recipe[1]) > 3 else ''})"
            for recipe, listings in sorted(held.items())
        )
        return TableNameError(
            f"table {table} already holds {len(held)} different recipes, as {which} list them "
            "(written by an rtde-spec that numbered tables per capture), and this capture has one of "
            "them: decode into a new folder, or remove that table's folder and those listings first",
            subject=f"folder {self.outdir}",
        )


def listing_entries(path: Path) -> list[tuple[str, Recipe]]:
    """(table, recipe) of one listing, read once per version of the file."""
    try:
        st = path.stat()
        key = (st.st_ino, st.st_mtime_ns, st.st_size)  # a rewrite is a new file (renamed in)
        cached = _listings.get(str(path))
        if cached is not None and cached[0] == key:
            return cached[1]
        data = json.loads(path.read_bytes())
    except FileNotFoundError:  # removed since the folder was listed (its capture re-run elsewhere)
        return []
    except (OSError, ValueError) as exc:
        why = (
            f"cannot be read ({exc}): it says which recipe each table of its capture holds, so no "
            "table name can be given safely"
        )
        raise _unusable(path, why) from exc
    try:
        entries = [(str(e["table"]), (str(e["direction"]), tuple(str(n) for n in e["names"]))) for e in data]
    except (TypeError, KeyError) as exc:
        raise _unusable(
            path, f"is not a list of tables with their direction and field names (no {exc})"
        ) from exc
    if len(_listings) >= _CACHE_MAX:
        _listings.clear()
    _listings[str(path)] = (key, entries)
    return entries


def _unusable(path: Path, why: str) -> OutputError:
    """A listing no name can be checked against: what to do about it."""
    return OutputError(f"{why}: restore it, or remove it with that capture's files", subject=f"file {path}")


@contextmanager
def folder_lock(outdir: str | Path) -> Iterator[None]:
    """The output folder held by this process alone while it checks names and places tables
    (other captures writing into it: `capture_bag` on Dask, a second command). An advisory lock
    on the folder itself, so no file is added to it; where none can be taken, none is."""
    try:
        import fcntl
    except ImportError:  # Windows: no advisory locks on folders
        yield
        return
    try:
        fd = os.open(outdir, os.O_RDONLY)
    except OSError:
        yield
        return
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:  # a file system without locks
            pass
        yield
    finally:
        os.close(fd)
