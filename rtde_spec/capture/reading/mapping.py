"""The capture file mapped into memory: a block's pages brought in at once and given back after.

Reading a big capture through a mapping copies nothing; the pages of blocks done leave
memory, so what a run holds stays bounded whatever the file's size.
"""

from __future__ import annotations

import mmap
import sys
from typing import IO

MADV_POPULATE_READ = getattr(mmap, "MADV_POPULATE_READ", 22)  # Linux's value; Python 3.11 lacks the name


def give_back(mapped: mmap.mmap, start: int, end: int) -> None:
    """The whole pages of file bytes start..end-1, done with, leave memory."""
    page = mmap.ALLOCATIONGRANULARITY
    if hasattr(mapped, "madvise") and end // page > start // page:
        mapped.madvise(mmap.MADV_DONTNEED, start // page * page, (end // page - start // page) * page)


def populate(mapped: mmap.mmap, start: int, end: int) -> None:
    """Map a block's pages in one call (Linux 5.14+) rather than a fault per few pages."""
    if sys.platform == "linux":
        try:
            mapped.madvise(MADV_POPULATE_READ, start, end - start)
        except OSError:  # an older kernel: the pages fault in as they are read
            pass


def mapped_file(f: IO[bytes]) -> mmap.mmap | None:
    """The whole file mapped read-only, or None where it cannot be (a pipe, an empty file).

    A capture still being written is read up to its size when opened, as a read would
    at that moment.
    """
    try:
        return mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
    except (OSError, ValueError, AttributeError):  # io.UnsupportedOperation is an OSError
        return None
