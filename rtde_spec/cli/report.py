"""Exit codes, and what --lenient left out, said the same way by every subcommand."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rtde_spec.errors import DecodeError
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
