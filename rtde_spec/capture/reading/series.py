"""Captures split into parts: a ring buffer (`dumpcap -b`, `tshark -b`), `editcap -c N` / `-i S`,
`tcpdump -C` / `-W`. Each part is a whole capture file, but a connection runs on from one part
into the next: its setup exchange (RTDE recipes, the URCL program) is in the part it began in.

`parts_of` names a file's series and its place in it; `group` orders files into series, so
that the parts can be decoded as one capture (`packets.items` takes a list of parts); `earlier`
finds the parts before a file beside it, so a part decoded alone can say where its setup went.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

from rtde_spec.capture.reading.compressed import SUFFIXES as COMPRESSED

# dumpcap/tshark -b and editcap -c/-i: PREFIX_NNNNN_YYYYMMDDhhmmss[.EXT]
_NUMBERED = re.compile(r"^(?P<prefix>.+)_(?P<n>\d{5,})_(?P<when>\d{14})(?P<ext>(?:\.[A-Za-z0-9]+)*)$")
# a capture's name: .pcap, .pcapng, .cap, tcpdump -C's numbered .pcapN, compressed whole or not
_PACKED = "|".join(re.escape(suffix[1:]) for suffix in COMPRESSED)
CAPTURE_NAME = re.compile(rf"\.(?:pcap|pcapng|cap)\d*(?:\.(?:{_PACKED}))?$", re.IGNORECASE)
# tcpdump -C (and -W): NAME, NAME1, NAME2, ... (-W pads the numbers: NAME00, NAME01, ...)
_TCPDUMP = re.compile(r"^(?P<prefix>.+\.(?:pcap|pcapng|cap))(?P<n>\d*)$")


class Part(NamedTuple):
    series: str  # a shell glob of every part of the series: its folder, prefix and suffix
    number: int  # its place: parts decode in this order
    in_order: bool = False  # whether the glob lists the parts in order (numbers padded alike)


def parts_of(path: str | Path) -> Part | None:
    """The series `path` is a part of, and its number; None for a name no splitting tool writes."""
    path = Path(path)
    found = _NUMBERED.match(path.name)
    if found:
        key = f"{path.parent / found['prefix']}_*{found['ext']}"
        return Part(key, int(found["n"]), in_order=True)
    found = _TCPDUMP.match(path.name)
    if found and found["n"]:
        return Part(str(path.parent / found["prefix"]) + "*", int(found["n"]))
    return None


def capture_files(folder: Path) -> list[Path]:
    """The captures in a folder and its subfolders, in path order, by name: `.pcap`, `.pcapng`,
    `.cap`, the parts tcpdump -C numbers (`x.pcap1`), and those compressed whole (`x.pcapng.gz`)."""
    return sorted(p for p in folder.rglob("*") if CAPTURE_NAME.search(p.name) and p.is_file())


def group(files: Sequence[Path]) -> list[list[Path]]:
    """The files as captures: the parts of one series together, in their order, where the first of
    them stood; every other file alone. (tcpdump's first part has no number: it is part 0.)"""
    series: dict[str, list[tuple[int, Path]]] = {}
    order: list[str | Path] = []
    for f in files:
        part = parts_of(f) or _tcpdump_first(f, files)
        if part is None:
            order.append(f)
            continue
        if part.series not in series:
            series[part.series] = []
            order.append(part.series)
        series[part.series].append((part.number, f))
    return [[key] if isinstance(key, Path) else [p for _, p in sorted(series[key])] for key in order]


def _tcpdump_first(f: Path, files: Sequence[Path]) -> Part | None:
    """tcpdump -C's first file (NAME, no number) when its numbered parts are among `files`."""
    key = str(f) + "*"
    if any(p != f and (parts_of(p) or Part("", 0)).series == key for p in files):
        return Part(key, -1)
    return None


def earlier(path: str | Path) -> list[Path]:
    """The parts of `path`'s series beside it that come before it, in order (none: not a part, or
    the first, or a ring buffer that dropped them)."""
    part = parts_of(path)
    if part is None:
        return []
    found = []
    for other in Path(path).parent.iterdir():
        theirs = parts_of(other)
        if theirs is not None and theirs.series == part.series and theirs.number < part.number:
            found.append((theirs.number, other))
    if part.series.endswith("*") and not _NUMBERED.match(Path(path).name):  # tcpdump: NAME itself first
        first = Path(part.series[:-1])
        if first.is_file():
            found.append((-1, first))
    return [p for _, p in sorted(found)]
