"""Exit codes, and what --lenient left out, said the same way by every subcommand."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from rtde_spec.errors import RtdeSpecError

if TYPE_CHECKING:
    from rtde_spec.errors import DecodeError
    from rtde_spec.output.base import Writer
    from rtde_spec.wire.framing import Skipped

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2


def report_skipped(skipped: Skipped, fault: DecodeError | None, unframed: str, unit: str) -> None:
    """What --lenient left out, on stderr: counts, bytes, the first offsets and reasons.

    `unframed` says how much of the input from a framing fault on went undecoded.
    """
    if skipped.count:
        print(
            f"note: --lenient skipped {skipped.count} {unit}{'' if skipped.count == 1 else 's'} "
            f"that did not decode ({skipped.bytes} bytes)",
            file=sys.stderr,
        )
        for offset, reason in skipped.first:
            print(f"  at byte {offset}: {reason}", file=sys.stderr)
        if skipped.count > len(skipped.first):
            print(f"  ... and {skipped.count - len(skipped.first)} more", file=sys.stderr)
    if fault is not None:
        print(
            f"note: --lenient: the input from byte {fault.offset} on ({unframed}) was not decoded: {fault}",
            file=sys.stderr,
        )


def close_output(writer: Writer, failure: BaseException | None, unit: str) -> None:
    """End a decode's output. Standard output has streamed every `unit` before a fault: it is
    flushed. A file is in place only when the run ended well: after a fault (strict), an error
    or an interrupt it is dropped, a file that was there stays as it was, and the fault says
    so (a partial file in place of a good one would be data lost with no word)."""
    part = writer.part
    if part is None:  # standard output: a full disk under it is said as its own
        full = _disk_full(failure)
        try:
            writer.close()
        except OSError as exc:  # the flush of what was held: the same full disk, or its first sign
            if full is None and (failure is not None or not _disk_full(exc)):
                raise
            full = full or exc
        if full is not None:
            from rtde_spec.errors import OutputError

            said = "writing failed: the disk is full"
            raise OutputError(said, errno=full.errno, subject="standard output") from full
        return
    if failure is None or part.failed is not None:
        writer.close()  # a failed write (a full disk) raises here, saying what stays at the name
        return
    rows = writer.rows
    writer.abort()
    from rtde_spec.cli.conventions import plural

    if rows and isinstance(failure, RtdeSpecError):
        was = "; the file that was there is as it was" if part.replaces else ""
        were = "was" if rows == 1 else "were"
        failure.extend(
            f"the {plural(rows, unit)} before it {were} not written to {part.target} (no partial file{was}); "
            "--lenient skips what does not decode and writes the rest"
        )


def _disk_full(exc: BaseException | None) -> OSError | None:
    """`exc` when it is a full disk no file of ours names (so standard output's: every file
    output names itself), else None."""
    import errno

    if not isinstance(exc, OSError) or isinstance(exc, RtdeSpecError):
        return None
    return exc if exc.errno in (errno.ENOSPC, errno.EDQUOT) else None
