"""The conventions every subcommand follows, in one place (docs/cli.md has the table).

-o/--output names every output (a folder when it ends in / or is one); --format is an
output format only (--input-format for inputs); --json prints one JSON document and
--jsonl a stream; the global options are accepted after the subcommand too; every
--help has a one-paragraph description and 2-4 examples. tests/test_cli_conventions.py
checks each subcommand's parser against them.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
from collections.abc import Callable, Sequence
from importlib.abc import Traversable
from pathlib import Path
from typing import Any

from rtde_spec.errors import UsageError

GLOBAL_AFTER = "extra_fields_after"  # --extra-fields given after the subcommand, merged in main


def describe(paragraph: str, *examples: str) -> dict[str, Any]:
    """add_parser() keywords: the description paragraph and an 'examples:' epilog, kept as written."""
    if not 2 <= len(examples) <= 4:
        raise ValueError("give 2-4 examples")
    epilog = "examples:\n" + "\n".join(f"  {line}" for line in examples)
    return {
        "description": paragraph,
        "epilog": epilog,
        "formatter_class": argparse.RawDescriptionHelpFormatter,
    }


def add_global_options(parser: argparse.ArgumentParser) -> None:
    """--debug and --extra-fields after the subcommand as well as before it (hidden: the top help
    has them)."""
    parser.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    parser.add_argument(
        "--extra-fields", action="append", dest=GLOBAL_AFTER, default=argparse.SUPPRESS, metavar="YAML",
        help=argparse.SUPPRESS,
    )  # fmt: skip


def leaf_parsers(parser: argparse.ArgumentParser) -> list[tuple[str, argparse.ArgumentParser]]:
    """(command words, parser) of every subcommand that runs, nested ones (spec import) included."""
    out: list[tuple[str, argparse.ArgumentParser]] = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                nested = leaf_parsers(child)
                out += [(f"{name} {words}", p) for words, p in nested] if nested else [(name, child)]
    return out


def plural(count: int, word: str, many: str | None = None) -> str:
    """'1 connection', '2 connections' ('1 row', '0 rows')."""
    return f"{count} {word if count == 1 else many or word + 's'}"


def dangling_link(path: Path) -> str | None:
    """What is wrong with an output folder that is a symbolic link to nothing (making it failed
    as "File exists"), or None."""
    if not path.is_symlink() or path.exists():
        return None
    try:
        target = os.readlink(path)
    except OSError:
        target = "?"
    return f"is a symbolic link to {target}, which does not exist; make that folder, or give another"


def output_folder(text: str, option: str = "-o") -> Path:
    """A folder output: refused when it names an existing file (a folder is made when missing) or
    is `-`, which means standard output everywhere else."""
    if text == "-":
        raise UsageError(
            "standard output cannot hold a folder of files; give a folder", subject=f"{option} -"
        )
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise UsageError(
            "is a file, but this output is a folder (one file per table); give a folder, e.g. "
            f"{path.stem or 'out'}/",
            subject=f"{option} {text}",
        )
    broken = dangling_link(path)
    if broken is not None:
        raise UsageError(broken, subject=f"{option} {text}")
    in_the_way = file_in_the_way(path)
    if in_the_way is not None:
        raise UsageError(in_the_way, subject=f"{option} {text}")
    return path


def file_in_the_way(path: Path) -> str | None:
    """Why a folder cannot be made at `path`: the nearest part of it that exists is a file (it was
    found only when a file under it was written: "Not a directory", "File exists"); else None."""
    above = next((p for p in path.parents if p.exists() or p.is_symlink()), None)
    if above is None or above.is_dir():
        return None
    return f"{above} is a file, not a folder; give a path in a folder"


def output_file(text: str, option: str = "-o") -> Path:
    """A file output: its folder must exist (and be a folder); a folder is refused. Checked before
    anything connects or is read, so the error names the path the user gave, in plain words.
    `-` (standard output) is refused: a command that writes there takes it before asking."""
    if text == "-":
        raise UsageError(
            "this output is a file, written whole at the end; give a file name", subject=f"{option} -"
        )
    path = Path(text)
    if names_folder(text):
        raise UsageError(
            "is a folder, but this output is one file; give a file name", subject=f"{option} {text}"
        )
    parent = path.parent
    if parent.exists() and not parent.is_dir():
        raise UsageError(
            f"{parent} is a file, not a folder; give a path in a folder", subject=f"{option} {text}"
        )
    if not parent.exists():
        raise UsageError(
            f"the folder {parent} does not exist; make it first (mkdir -p {parent}) or give another path",
            subject=f"{option} {text}",
        )
    return path


def names_folder(text: str) -> bool:
    """-o names a folder when it ends in / or is an existing folder."""
    return text.endswith(("/", "\\")) or Path(text).is_dir()


def place_copy(source: Path | Traversable, target: Path, refuse: Callable[[str], UsageError]) -> None:
    """`source`'s bytes as `target`, as every output is written (`partfile`: beside the name,
    renamed when whole, through a symlink; a failed write leaves no temporary file and the
    file that was there as it was). A full disk raises the write error, naming the file
    (exit 1); any other failure `refuse(why)`: the folder given is the problem (exit 2)."""
    place_copies([(source, target)], lambda why, _: refuse(why))


def place_copies(
    copies: Sequence[tuple[Path | Traversable, Path]], refuse: Callable[[str, Path], UsageError]
) -> None:
    """Each `(source, target)` as `place_copy` writes it, the set in place together or not at
    all: every file is written beside its name first, then each is renamed. (A set cut short
    by a full disk was refused as "already there" when run again.) A failed write leaves the
    files that were there as they were, and no file or folder this call made. A full disk
    raises the write error naming the file; any other failure `refuse(why, target)`."""
    from rtde_spec.output.partfile import NO_ROOM, Part, PartStream, write_failed

    parts: list[Part] = []
    made = _missing_folders([target.parent for _, target in copies])
    target = copies[0][1] if copies else Path()
    try:
        for source, target in copies:
            target.parent.mkdir(parents=True, exist_ok=True)
            parts.append(Part(target))
            with source.open("rb") as src, PartStream(parts[-1], batched=False) as out:
                shutil.copyfileobj(src, out)
        for part, (_, target) in zip(parts, copies, strict=True):  # noqa: B007  # named if it fails
            part.commit()  # a rename can fail too (a full directory): the files before it are in place
    except BaseException as exc:
        for part in parts:
            part.discard()
        for folder in made:  # the deepest first; one that holds a file now (a rename above) stays
            with contextlib.suppress(OSError):
                folder.rmdir()
        if not isinstance(exc, OSError):
            raise
        failed = write_failed(exc, target)
        if failed.errno in NO_ROOM:
            raise failed from None
        raise refuse(failed.reason.removeprefix("writing failed: "), target) from None


def _missing_folders(folders: Sequence[Path]) -> list[Path]:
    """The folders (and their parents) that do not exist yet, the deepest first."""
    missing: set[Path] = set()
    for folder in folders:
        while not folder.exists() and not folder.is_symlink() and folder != folder.parent:
            missing.add(folder)
            folder = folder.parent
    return sorted(missing, key=lambda f: len(f.parts), reverse=True)
