"""Argument types every subcommand shares: files, recipes, ports, controller versions, the catalogue.

Kept free of heavy imports so `rtde-spec --help` starts fast; what needs the spec
or pydantic imports it inside the function.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rtde_spec.errors import RtdeSpecError, UsageError
from rtde_spec.output.partfile import kind_of

if TYPE_CHECKING:
    from rtde_spec.metamodel.catalogue import Catalogue


def catalogue_for(args: argparse.Namespace) -> Catalogue:
    """The built-in catalogue plus $RTDE_SPEC_EXTRA_FIELDS and --extra-fields files."""
    from rtde_spec.metamodel.catalogue import Catalogue

    base = Catalogue.default()
    extra = getattr(args, "extra_fields", None)
    for name in extra or ():
        if existing_file(name) is None:
            raise UsageError(
                "no such file; --extra-fields takes a YAML file shaped like spec/rtde/fields.yaml "
                "(outputs: / inputs: lists of name and type)",
                subject=f"--extra-fields {name}",
            )
    return base.with_extra(*extra) if extra else base


def existing_file(arg: str) -> Path | None:
    """The path if `arg` names an existing regular file; None if not (a too-long name is not a file).

    A directory, a FIFO or a device is a usage error: it is neither a file nor data.
    """
    if not arg or arg == "-" or "\x00" in arg:
        return None
    path = Path(arg)
    try:
        if path.is_file():
            return path
        if path.is_dir():
            raise UsageError("is a directory, not a file", subject=f"file {arg}")
        kind = kind_of(path)  # a FIFO, a device: read once, never seekable, often never ending
        if kind is not None:
            raise UsageError(f"is {kind}, not a regular file; give a file", subject=f"file {arg}")
    except OSError:  # e.g. ENAMETOOLONG for a long hex string: not a file
        return None
    return None


RECIPE_FILE_HELP = (
    "a recipe file: UR's XML (rtde_config, as record_configuration.xml), YAML, JSON, or one name per line"
)


def recipe_file(arg: str, option: str = "--recipe") -> Path | None:
    """The recipe file `arg` names, or None when it is a comma list of names (field names hold
    no '.' or '/'): a name that looks like a file but is none is a missing file, not a field."""
    path = existing_file(arg)
    if path is not None:
        return path
    if "," not in arg and ("/" in arg or os.sep in arg or "." in arg):
        raise UsageError(
            f"no such recipe file; give {RECIPE_FILE_HELP}, or field names as a comma list "
            "(e.g. timestamp,actual_q)",
            subject=f"{option} {arg[:200]}",
        )
    return None


def port_number(text: str) -> int:
    """argparse type of a TCP port: 0..65535 (0: any free port where a port is listened on)."""
    try:
        number = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number (0..65535)") from None
    if not 0 <= number <= 65535:
        raise argparse.ArgumentTypeError(f"{number} is not a port number: give 0..65535")
    return number


def port_or_off(text: str) -> int:
    """argparse type of a port that may be left out: -1 (not served) or 0..65535."""
    return -1 if text.strip() == "-1" else port_number(text)


_FULL_VERSION = re.compile(r"^\d+\.\d+\.\d+(\.\d+)?$")


def controller_version(text: str) -> str:
    """argparse type of --controller: MAJOR.MINOR.BUGFIX of a known product line, or exit 2.

    A release outside what the spec knows (newer than its newest, older than the line's
    first) is taken, with a warning naming the nearest known release.
    """
    if not _FULL_VERSION.match(text.strip()):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a controller version: give MAJOR.MINOR.BUGFIX, e.g. 5.12.2 or 3.15.8"
        )
    release_version(text)
    note = unknown_release(text)
    if note:
        print(f"warning: --controller {text}: {note}", file=sys.stderr)
    return text


def primary_version(text: str) -> str:
    """argparse type of capture's --controller: any MAJOR.MINOR[.BUGFIX], older firmware too (CB2's
    1.x has primary layouts of its own); one outside the spec's lines is said in the summary."""
    from rtde_spec.metamodel.versions import Version

    try:
        Version.parse(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a controller version: give MAJOR.MINOR[.BUGFIX], e.g. 1.8, 3.3.1 or 5.15.0"
        ) from None
    return text


def release_version(text: str) -> str:
    """argparse type of a release (MAJOR.MINOR allowed, as in `fields --diff 5.10 5.11`)."""
    from rtde_spec.metamodel.catalogue import Catalogue

    try:
        Catalogue.builtin().line_of(text)
    except RtdeSpecError as exc:
        raise argparse.ArgumentTypeError(exc.reason) from None
    return text


def unknown_release(text: str) -> str | None:
    """Why the spec may not describe this release (None when it is within what it knows: from the
    line's first release to one minor release past the newest any field names)."""
    from rtde_spec.metamodel.catalogue import Catalogue
    from rtde_spec.metamodel.versions import Version

    catalogue = Catalogue.builtin()
    version = Version.parse(text)
    line = catalogue.line_of(version)
    known = {Version.parse(line.first_version)}
    known |= {v for info in catalogue.fields() for ln, v in info.since.items() if ln == line.id}
    newest, first = max(known), min(known)
    # the newest release naming a field may precede the newest without new fields (CB3's 3.15
    # added none): one minor release past it is taken as known
    if (version.major, version.minor) > (newest.major, newest.minor + 1):
        return (
            f"newer than the newest {line.name} release the spec knows ({newest}): fields added "
            f"since are missing (nearest known: {newest}; `rtde-spec spec import` reads a newer guide)"
        )
    if version < first:
        return f"older than the first {line.name} release with RTDE ({first}; nearest known: {first})"
    return None
