"""Files that appear at their name only when there is something to keep.

Every file output is written to a hidden file beside its target, `.NAME.part-PID`
(same directory, so the rename is atomic), and renamed into place when its writer
closes after rows were written. A run that fails before its first row leaves an
existing file byte-identical and no temporary file behind. A *live* file (a
recording's CSV or JSON Lines) is renamed into place as soon as its first batch is
on disk and then grows batch by batch, so a killed recorder leaves every batch but
the one being collected under the name asked for — unless a file is already there:
then the new one stays beside it until complete (a kill leaves both).

A write that fails (a full disk) ends the file: it is never committed, and a live file
already in place is cut back to its last whole batch, so no reader meets a torn line.
"""

from __future__ import annotations

import errno
import io
import os
import stat
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO, TypeVar, cast

from rtde_spec.errors import OutputError, out_of_descriptors
from rtde_spec.output.tempnames import temp_path

T = TypeVar("T")

SPILL = 8 << 20  # held bytes handed to the file before a flush, so memory stays bounded
# write errors of the data, not of the path given (a full disk, a failing device): exit 1, not 2
NO_ROOM = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EIO})


def is_special(target: Path) -> bool:
    """A device or pipe (`-o /dev/null`, a FIFO): written directly, never replaced."""
    try:
        mode = target.stat().st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode) and not stat.S_ISDIR(mode)


def is_fifo(target: Path) -> bool:
    """A named pipe: written in order only (a writer that seeks cannot use one)."""
    try:
        return stat.S_ISFIFO(target.stat().st_mode)
    except OSError:
        return False


KINDS = {
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFSOCK: "a socket",
    stat.S_IFDIR: "a directory",
}


def kind_of(path: Path) -> str | None:
    """What an existing path that is not a regular file is ("a FIFO (named pipe)"), for errors that
    say why it cannot be used; None for a regular file or nothing there."""
    try:
        mode = path.stat().st_mode
    except (OSError, ValueError):  # nothing there, a name too long, a NUL: not a special file
        return None
    return None if stat.S_ISREG(mode) else KINDS.get(stat.S_IFMT(mode), "not a regular file")


class Part:
    """A target file and the temporary file it is written as; `commit` or `discard` ends it.

    `failed` holds the first write error (a full disk): such a part is never committed,
    and a live one already in place keeps only whole batches (see `PartStream`).
    """

    def __init__(self, target: str | Path, *, durable: bool = False) -> None:
        path = Path(target)
        if path.is_symlink():  # write through the link, as opening it would
            path = Path(os.path.realpath(path))
        self.target = path
        self.temp = temp_path(path)
        self.durable = durable  # fsync before the rename: a closed file survives a power loss
        self.published = False
        self.placed: Callable[[], None] | None = None  # called once when the target holds our data
        self.failed: OutputError | None = None  # the write error that ended this file, if one did
        self.kept = 0  # bytes of a live file in place when it failed (whole batches only)
        # a live file goes in place early only where nothing is there to lose: an existing
        # file stays as it was until this one is complete
        self.replaces = path.exists()
        self.in_folder = path.parent.is_dir()  # (a folder gone later was another capture's pruning)

    def publish(self) -> None:
        """Rename into place now; later writes go on through the open file (a live file).

        Not while it would replace an existing file, nor after a failed write."""
        if not self.published and not self.replaces and self.failed is None:
            self._rename()
            self.published = True
            self._placed()

    def move_to(self, target: Path) -> None:
        """Another name for a file not yet in place: its temporary file moves beside `target`
        (a capture's table renamed before it is placed; the folder is made)."""
        if self.published:
            raise ValueError(f"{self.target} is in place already")
        temp = temp_path(target)
        try:
            temp.parent.mkdir(parents=True, exist_ok=True)
            os.replace(self.temp, temp)
        except OSError as exc:
            raise write_failed(exc, target) from exc
        self.target, self.temp, self.replaces = target, temp, target.exists()

    def commit(self) -> None:
        """The written file becomes the target (synced first when `durable`)."""
        if self.failed is not None:
            raise self.failed
        if self.durable:
            _fsync(self.target if self.published else self.temp)
        if not self.published:
            self._rename()
            self.published = True
            self._placed()
        if self.durable:
            _fsync_dir(self.target.parent)

    def _rename(self) -> None:
        """The temporary file to its name (a new directory entry can need a block: a full disk too)."""
        try:
            os.replace(self.temp, self.target)
        except OSError as exc:
            self.failed = write_failed(exc, self.target)
            raise self.failed from exc

    def discard(self) -> None:
        """Remove the temporary file; an existing target stays as it was. Called while an error
        is on its way: a file system that refuses the removal too (read-only: the file was never
        made) must not put its own error in place of the one that says what went wrong."""
        if not self.published:
            try:
                self.temp.unlink(missing_ok=True)
            except OSError:
                pass

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
        try:  # no room for one more file (no inode, no block for its entry) is a full disk too
            self._file: io.FileIO | None = open(part.temp, "wb", buffering=0)  # closed by close()
        except OSError as exc:
            part.failed = write_failed(exc, part.target)
            raise part.failed from exc
        self._held: list[bytes] = []  # blocks since the last flush, kept as given (no copy of bytes)
        self._held_size = 0
        self._batched = batched
        self.written = 0  # bytes written so far (held ones included): for splitting by size
        self.on_disk = 0  # bytes the file holds for sure: whole batches

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self._opened().fileno()

    def tell(self) -> int:
        return self.written

    def suspend(self) -> None:
        """Hand back the file's descriptor until the next write (many files, few descriptors):
        the file is append-only, so reopening it at its end goes on where it stopped."""
        if not self.closed and self._file is not None:
            self._drain()
            file, self._file = self._file, None
            file.close()

    def _opened(self) -> io.FileIO:
        if self._file is None:
            self._file = open(self.part.temp, "ab", buffering=0)
        return self._file

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
        """All of `data`, or the file cut back to what it held before and the error kept."""
        part = self.part
        if part.failed is not None:
            raise part.failed
        with memoryview(data) as view:
            done = 0
            try:
                file = self._opened()
                while done < len(view):
                    done += file.write(view[done:]) or 0
            except OSError as exc:
                part.failed = write_failed(exc, part.target)
                part.kept = self.on_disk if part.published else 0
                try:  # no torn line: the file ends where the last whole batch ended
                    if self._file is not None:
                        os.ftruncate(self._file.fileno(), self.on_disk)
                except OSError:
                    pass
                raise part.failed from exc
        self.on_disk += len(data)

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
            try:
                if self._file is not None:
                    self._file.close()
            except OSError as exc:  # the last buffered bytes did not fit either
                if self.part.failed is None:
                    self.part.failed = write_failed(exc, self.part.target)
            super().close()


class DeviceStream(io.RawIOBase):
    """A device or pipe given as the output (`-o /dev/full`, a FIFO), written directly: a full
    disk behind it is an OutputError naming it; a closed pipe stays a BrokenPipeError."""

    def __init__(self, target: Path) -> None:
        super().__init__()
        self.target = target
        self._file = open(target, "wb", buffering=0)  # closed by close()

    def writable(self) -> bool:
        return True

    def write(self, block: bytes | bytearray | memoryview) -> int:  # type: ignore[override]
        with memoryview(block) as view:
            size, done = len(view), 0
            while done < size:
                try:
                    done += self._file.write(view[done:]) or 0
                except OSError as exc:
                    raise device_failed(exc, self.target) from exc
        return size

    def close(self) -> None:
        if not self.closed:
            self._file.close()
            super().close()


def device_failed(exc: OSError, target: Path) -> OSError:
    """A write error of a file written directly: a full disk named as one, anything else as it was."""
    failed = write_failed(exc, target)
    return failed if failed.errno in NO_ROOM else exc


def write_failed(exc: BaseException, target: Path) -> OutputError:
    """The error of a write to `target`, naming the file (never its temporary file) and saying why
    in words: a full disk as such, a read-only file system, a folder in the way."""
    if isinstance(exc, OutputError):  # already said, about the same file
        return exc
    code = getattr(exc, "errno", None)
    if code in (errno.ENOSPC, errno.EDQUOT) or "No space left" in str(exc):
        code, why = code or errno.ENOSPC, "the disk is full"
    elif code in (errno.EMFILE, errno.ENFILE):  # as cli/main.py says it for any other open
        why = out_of_descriptors()
    else:
        why = (_WHY.get(code) if code is not None else None) or getattr(exc, "strerror", None) or str(exc)
    return OutputError(f"writing failed: {why}", errno=code, subject=f"file {target}")


_WHY = {
    errno.EFBIG: "the file is larger than the file system allows",
    errno.EROFS: "the file system is read-only",
    errno.EISDIR: "a directory has that name; give a file name",
    errno.ENOTDIR: "a part of the path is a file, not a folder",
    errno.EEXIST: "a part of the path is a file, not a folder",  # its folder made where a file is
    errno.ENOENT: "its folder does not exist",
    errno.EACCES: "permission denied (the folder or file is not writable)",
    errno.EPERM: "the operation is not permitted there",
    errno.EIO: "an input/output error of the device",
    errno.ENAMETOOLONG: "the name is too long",
}


def in_its_folder(open_file: Callable[[], T], part: Part | None) -> T:
    """`open_file()` of a part's temporary file, its folder made again if it is gone since the part
    began: a table's folder is made at its first row, a pinned Parquet file at its first row
    group, and another capture's placing (`capture --jobs N`) may prune the empty folder between."""
    try:
        return open_file()
    except FileNotFoundError:
        if part is None or not part.in_folder:
            raise
        part.temp.parent.mkdir(parents=True, exist_ok=True)
        return open_file()


def write_whole(target: str | Path, data: bytes, *, durable: bool = False) -> None:
    """A small file written at once (a listing, a summary), appearing only complete."""
    write_with(target, lambda out: out.write(data), durable=durable)


def write_with(
    target: str | Path,
    fill: Callable[[BinaryIO], object],
    *,
    durable: bool = False,
    keep_mode: bool = False,
) -> None:
    """A file that `fill` writes to a binary file object (an image, a copy, a document), appearing
    only complete: an existing file stays byte-identical if anything fails, no temporary file stays,
    and the error names `target`. A symlink is written through, as every output is; `keep_mode`
    gives the new file the mode of the one it replaces (a file edited in place)."""
    part = Part(target, durable=durable)
    if is_special(part.target):  # -o /dev/null, a pipe: nothing to replace
        with DeviceStream(part.target) as device:
            fill(cast(BinaryIO, device))
        return
    stream = PartStream(part, batched=False)  # a failed open is a write error naming target
    try:
        try:
            fill(cast(BinaryIO, stream))
        finally:
            stream.close()
        if keep_mode and part.replaces and part.failed is None:
            try:
                os.chmod(part.temp, stat.S_IMODE(part.target.stat().st_mode))
            except OSError as exc:
                part.failed = write_failed(exc, part.target)
        part.commit()  # raises the first write error, if one happened
    except BaseException as exc:
        part.discard()
        if isinstance(exc, OSError) and part.failed not in (None, exc):  # a writer that wrapped ours
            raise cast(OutputError, part.failed) from exc
        raise
