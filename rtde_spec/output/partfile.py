"""Files that appear at their name only when there is something to keep.

Every file output is written to a hidden file beside its target, `.NAME.part-PID`
(same directory, so the rename is atomic), and renamed into place when its writer
closes after rows were written. A run that fails before its first row leaves an
existing file byte-identical and no temporary file behind. A *live* file (a
recording's CSV or JSON Lines) is renamed into place as soon as its first batch is
on disk and then grows batch by batch, so a killed recorder leaves every batch but
the one being collected under the name asked for.
"""

from __future__ import annotations

import io
import os
import stat
from collections.abc import Callable
from pathlib import Path

PART_MARK = ".part-"
SPILL = 8 << 20  # held bytes handed to the file before a flush, so memory stays bounded


def temp_path(target: Path) -> Path:
    """Where `target` is written until it is renamed into place."""
    return target.with_name(f".{target.name}{PART_MARK}{os.getpid()}")


def is_special(target: Path) -> bool:
    """A device or pipe (`-o /dev/null`, a FIFO): written directly, never replaced."""
    try:
        mode = target.stat().st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode) and not stat.S_ISDIR(mode)


def leftovers(target: Path) -> list[Path]:
    """Temporary files of `target` (and of its split parts) whose process is gone: a killed run."""
    folder = target.parent
    stem, suffix = target.stem, target.suffix
    found = []
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    for name in names:
        if not name.startswith(f".{stem}") or PART_MARK not in name:
            continue
        real, _, pid = name[1:].rpartition(PART_MARK)
        if not real.endswith(suffix) or not pid.isdigit() or _alive(int(pid)):
            continue
        if real == target.name or real[len(stem) :].lstrip("_").removesuffix(suffix).isdigit():
            found.append(folder / name)
    return sorted(found)


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


class Part:
    """A target file and the temporary file it is written as; `commit` or `discard` ends it."""

    def __init__(self, target: str | Path, *, durable: bool = False) -> None:
        path = Path(target)
        if path.is_symlink():  # write through the link, as opening it would
            path = Path(os.path.realpath(path))
        self.target = path
        self.temp = temp_path(path)
        self.durable = durable  # fsync before the rename: a closed file survives a power loss
        self.published = False
        self.placed: Callable[[], None] | None = None  # called once when the target holds our data

    def publish(self) -> None:
        """Rename into place now; later writes go on through the open file (a live file)."""
        if not self.published:
            os.replace(self.temp, self.target)
            self.published = True
            self._placed()

    def commit(self) -> None:
        """The written file becomes the target (synced first when `durable`)."""
        if self.durable:
            _fsync(self.target if self.published else self.temp)
        if not self.published:
            os.replace(self.temp, self.target)
            self.published = True
            self._placed()
        if self.durable:
            _fsync_dir(self.target.parent)

    def discard(self) -> None:
        """Remove the temporary file; an existing target stays as it was."""
        if not self.published:
            self.temp.unlink(missing_ok=True)

    def _placed(self) -> None:
        if self.placed is not None:
            placed, self.placed = self.placed, None
            placed()


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(path: Path) -> None:
    try:
        _fsync(path)
    except OSError:  # not every system opens directories
        pass


class PartStream(io.RawIOBase):
    """The temporary file of a `Part`, as a binary stream.

    With `batched`, bytes reach the file only at `flush` (or past `SPILL` held bytes),
    in one write: a process killed between flushes leaves whole batches, never half a line.
    """

    def __init__(self, part: Part, *, batched: bool = True) -> None:
        super().__init__()
        self.part = part
        self._file = open(part.temp, "wb", buffering=0)  # closed by close()
        self._held: list[bytes] = []  # blocks since the last flush, kept as given (no copy of bytes)
        self._held_size = 0
        self._batched = batched
        self.written = 0  # bytes written so far (held ones included): for splitting by size

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self._file.fileno()

    def write(self, block: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        size = len(block)
        self.written += size
        if not self._batched:
            self._write_all(block)
            return size
        self._held.append(block if isinstance(block, bytes) else bytes(block))
        self._held_size += size
        if self._held_size >= SPILL:
            self._drain()
        return size

    def _drain(self) -> None:
        if self._held:
            held = self._held[0] if len(self._held) == 1 else b"".join(self._held)
            self._held, self._held_size = [], 0
            self._write_all(held)

    def _write_all(self, data: bytes | bytearray | memoryview) -> None:
        with memoryview(data) as view:
            done = 0
            while done < len(view):
                done += self._file.write(view[done:]) or 0

    def flush(self) -> None:
        """Everything written so far is handed to the operating system."""
        if not self.closed:
            self._drain()

    def close(self) -> None:
        if self.closed:
            return
        try:
            self._drain()
        finally:
            self._file.close()
            super().close()


def write_whole(target: str | Path, data: bytes, *, durable: bool = False) -> None:
    """A small file written at once (a listing, a summary), appearing only complete."""
    part = Part(target, durable=durable)
    if is_special(part.target):
        part.target.write_bytes(data)
        return
    try:
        part.temp.write_bytes(data)
        part.commit()
    except BaseException:
        part.discard()
        raise
