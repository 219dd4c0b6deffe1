"""A capture's tables put in place: under names checked against the folder, all or none of them.

A capture's files are written beside their names and finished (`DirectorySink.prepare`);
`PreparedTables` then puts them in place, in this process or in the parent of `capture
--jobs N`, which places files in input order so table names do not depend on N
(`names.py`). Placing holds the folder's lock, checks that the folder still gives each
recipe the table its rows were written under, writes the capture's listing first (a table
in place is always in a listing), then renames the files with signals held.
"""

from __future__ import annotations

import glob
import itertools
import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import unquote

from rtde_spec.capture.tables.names import Recipe, Register, folder_lock, listing_entries, listing_name
from rtde_spec.capture.tables.signals import signals_held
from rtde_spec.errors import OutputError
from rtde_spec.output.partfile import Part, write_failed, write_whole
from rtde_spec.output.tempnames import leftovers

EXTENSIONS = {"parquet": "parquet", "csv": "csv", "jsonl": "jsonl", "mcap": "mcap"}  # format -> files' suffix


class NamesTaken(OutputError):
    """A capture's tables were not put in place: the folder gave a name they were written under
    to another recipe meanwhile (another capture placed first). Decoding it again names them right."""


@dataclass
class PreparedTables:
    """A capture's tables, finished beside their names: put in place (`place`) once their names
    are checked against the folder, or dropped (`discard`). Plain data, so the process that
    decoded them need not be the one that places them."""

    outdir: Path
    stem: str
    ext: str  # of the files (the format's)
    parts: list[Part]  # the files with rows, in the order they were finished
    paths: list[Path]
    recipes: dict[Recipe, str]  # each recipe's table, in the order the capture met them
    renamed: dict[str, str] = field(default_factory=dict)  # table written -> table placed, where they differ

    def place(self) -> bool:
        """Under the folder's lock: when the folder still gives each recipe the table it was
        written under, the listing and then every table go in place (each even after one fails:
        the first error is raised); False, with nothing touched, when it does not."""
        with folder_lock(self.outdir):
            register = Register.read(self.outdir)
            names = register.assign(list(self.recipes))
            if names != self.recipes:
                if self.ext == "mcap":  # its files name their table inside: decode it again
                    return False
                self._rename_tables(names)
            earlier = register.tables_of(listing_name(self.stem))
            self._remove_leftovers()
            # first, this run's tables beside the earlier run's: whatever stops the renames, every
            # table of either run stays in a listing, so no other capture is given its name
            self._write_listing(keep=listing_entries(self.outdir / listing_name(self.stem)))
            failed: BaseException | None = None
            with signals_held():  # renames only: all of this run's tables, or (before) none
                for part in self.parts:
                    try:
                        part.commit()
                    except Exception as exc:
                        part.discard()
                        failed = failed or exc
            self.parts = []
            if failed is not None:
                raise failed
            self._remove_stale_parts()
            self._remove_dropped_tables(earlier - set(self.recipes.values()))
            self._write_listing()  # this run's tables alone, now that the earlier run's are gone
        return True

    def _remove_leftovers(self) -> None:
        """Temporary files of this capture's listing and tables that a killed run left (`kill -9`
        cannot be cleaned up after by the process itself): their process is gone."""
        for target in {self.outdir / listing_name(self.stem), *(part.target for part in self.parts)}:
            for stale in leftovers(target):
                _remove(stale)

    def _rename_tables(self, names: dict[Recipe, str]) -> None:
        """Move the files of recipes the folder now names otherwise (another capture placed a new
        recipe under the name this one guessed) to their tables: rows hold no table name."""
        moved = {
            self.recipes[recipe]: table for recipe, table in names.items() if self.recipes[recipe] != table
        }
        for part in self.parts:
            before = part.temp.parent
            target = _renamed(part.target, self.outdir, moved)
            if target != part.target:
                part.move_to(target)
                prune(before, before.parent)  # robot=, date= folders it alone needed
        self.paths = [_renamed(path, self.outdir, moved) for path in self.paths]
        self.renamed.update(moved)
        self.recipes = dict(names)

    def discard(self) -> None:
        """Drop every table of this capture: files of earlier runs stay as they were."""
        for part in self.parts:
            part.discard()
        self.parts = []

    def _write_listing(self, keep: Sequence[tuple[str, Recipe]] = ()) -> None:
        """The capture's listing: its recipes' tables, and those of `keep` (an earlier run's
        entries) it does not give another recipe."""
        target = self.outdir / listing_name(self.stem)
        entries = [(t, recipe) for recipe, t in self.recipes.items()]
        entries += [(t, recipe) for t, recipe in keep if (t, recipe) not in entries]
        if not entries:  # none now: an earlier run's listing would hold names for nothing
            target.unlink(missing_ok=True)
            return
        listing = [{"table": t, "direction": d, "names": list(n)} for t, (d, n) in entries]
        try:
            write_whole(target, (json.dumps(listing, indent=2) + "\n").encode())  # whole or not at all
        except OSError as exc:
            self.discard()
            failed = write_failed(exc, target)
            kept = "the listing says which recipe each table holds, so none of the tables was put in place"
            raise OutputError(f"{failed.reason}: {kept}", errno=failed.errno, subject=failed.subject) from exc

    def _remove_stale_parts(self) -> None:
        """Files of an earlier run of this input that this run did not write, in the robots and
        days it writes: parts STEM_NNNN past this run's (it was shorter), and tables it no longer
        holds (the file changed: its primary tables stayed beside the new run's). Left, they
        would read as rows of this capture. Only this run's partitions are looked at, by name:
        the cost is the capture's own, not the dataset's (a year of a fleet's days)."""
        written = {str(p) for p in self.paths}
        partitions = {p.relative_to(self.outdir).parts[1:-1] for p in self.paths}
        tables = [t for t in self.outdir.iterdir() if t.is_dir()] if self.outdir.is_dir() else []
        for table in tables:
            for partition in partitions:
                folder = table.joinpath(*partition)
                removed = False
                for n in itertools.count():
                    old = folder / f"{self.stem}{f'_{n:04d}' if n else ''}.{self.ext}"
                    if not old.is_file():
                        break
                    if str(old) not in written:
                        removed = _remove(old) or removed
                if removed:  # only folders this emptied: an empty one may be another capture's, new
                    prune(folder, folder.parent, table)
        for folder in {p.parent for p in self.paths}:
            self._remove_unescaped(folder)

    def _remove_unescaped(self, folder: Path) -> None:
        """This input's files of an earlier version's run under the robot folder named with ':' as
        '_' (`robot=fd00__d3`, not `robot=fd00%3A%3Ad3`): left, they would be a second robot."""
        robot = folder.parent
        key, _, value = robot.name.partition("=")
        legacy = robot.with_name(f"{key}={unquote(value).replace(':', '_')}") / folder.name
        if legacy == folder or not legacy.is_dir():
            return
        stem = glob.escape(self.stem)
        removed = False
        for pattern in (f"{stem}.{self.ext}", f"{stem}_[0-9][0-9][0-9][0-9].{self.ext}"):
            for old in legacy.glob(pattern):
                removed = _remove(old) or removed
        if removed:
            prune(legacy, legacy.parent)

    def _remove_dropped_tables(self, tables: set[str]) -> None:
        """This input's files in recipe tables an earlier run of it wrote and this one did not (the
        file changed): left, they would hold rows of a recipe the listings no longer give that name."""
        stem = glob.escape(self.stem)
        for table in sorted(tables):
            for ext in EXTENSIONS.values():  # whichever format an earlier run wrote
                for pattern in (f"{stem}.{ext}", f"{stem}_[0-9][0-9][0-9][0-9].{ext}"):
                    for old in (self.outdir / table).glob(f"*/*/{pattern}"):
                        _remove(old)


def _renamed(path: Path, outdir: Path, moved: dict[str, str]) -> Path:
    """`path` (OUTDIR/TABLE/...) in the table `moved` gives its table, if it gives one."""
    table, *rest = path.relative_to(outdir).parts
    return outdir.joinpath(moved[table], *rest) if table in moved else path


def prune(*folders: Path) -> None:
    """Remove each of `folders` in turn while it is empty (date=, robot=, a table's own)."""
    for empty in folders:
        try:
            empty.rmdir()
        except OSError:  # not empty, or gone
            break


def _remove(path: Path) -> bool:
    """Whether the file was removed."""
    try:
        path.unlink()
    except OSError:  # gone already, or not ours to remove: the summary lists ours
        return False
    return True
