"""Names of the temporary files outputs are written as until they are renamed into place, and
finding those a killed run left behind (`record` says so and removes them).

`.NAME.part-PID`, beside NAME: hidden, and the process id tells a live writer's file from a dead
one's. A second file of the same target while the first is not yet in place (a capture given
twice, its first tables prepared for the parent to place) is `.NAME.part-PID-2`, and so on: one
must not truncate the other. A name too long to take the mark (a legal 244-byte output) is
shortened, with a checksum of the whole so its parts' temporary names stay apart.
"""

from __future__ import annotations

import os
import zlib
from pathlib import Path

PART_MARK = ".part-"
NAME_MAX = 255  # bytes of one file name on Linux's file systems (and macOS's)


def temp_path(target: Path) -> Path:
    """Where `target` is written until it is renamed into place: a name no file has yet."""
    base = f"{_temp_stem(target.name)}{PART_MARK}{os.getpid()}"
    path, count = target.with_name(base), 1
    while os.path.lexists(path):  # this process's own, not yet in place: the same target again
        count += 1
        path = target.with_name(f"{base}-{count}")
    return path


def _pid(tail: str) -> int | None:
    """The process id of a temporary name's tail after its mark (`PID` or `PID-N`)."""
    pid = tail.split("-", 1)[0]
    return int(pid) if pid.isdigit() else None


def _temp_stem(name: str) -> str:
    """The temporary file's name before its mark: `.NAME`, or for a name too long to take the
    mark and a process id (a legal 244-byte output), its start and a checksum of the whole."""
    stem = f".{name}"
    room = NAME_MAX - len(PART_MARK) - 16  # a pid has at most 7 digits on Linux, then -N; 3 to spare
    raw = os.fsencode(stem)
    if len(raw) <= room:
        return stem
    check = f"~{zlib.crc32(raw):08x}"
    return raw[: room - len(check)].decode("utf-8", "ignore") + check  # no character cut in two


def leftovers(target: Path) -> list[Path]:
    """Temporary files of `target` (and of its split parts) whose process is gone: a killed run."""
    folder = target.parent
    stem, suffix = target.stem, target.suffix
    found = []
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    shortened = _long_temp_stems(target) if _temp_stem(target.name) != f".{target.name}" else set()
    for name in names:
        head, _, tail = name.rpartition(PART_MARK)
        pid = _pid(tail)
        if head in shortened:  # a long name's temporary file (or one of its parts')
            if pid is not None and not _alive(pid):
                found.append(folder / name)
            continue
        if not name.startswith(f".{stem}") or PART_MARK not in name:
            continue
        real = name[1:].rpartition(PART_MARK)[0]
        if not real.endswith(suffix) or pid is None or _alive(pid):
            continue
        if real == target.name or real[len(stem) :].lstrip("_").removesuffix(suffix).isdigit():
            found.append(folder / name)
    return sorted(found)


def _long_temp_stems(target: Path) -> set[str]:
    """The shortened temporary stems of a long `target` and of its split parts (NAME_0000...)."""
    names = [target.name] + [f"{target.stem}_{index:04d}{target.suffix}" for index in range(10000)]
    return {_temp_stem(name) for name in names}


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, someone else's
        return True
    return True
