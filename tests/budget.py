"""How many examples a property test draws: all of them in CI, a quarter in the plain run.

The plain `pytest` is the contributor's loop and has a time budget (under 3 minutes on 2
cores, issue 28); CI (`.ci/run` sets RTDE_SPEC_SLOW=1) draws every example the test asks
for, so a rare case the quick run misses is still searched for before a merge.
"""

from __future__ import annotations

import os

FULL = os.environ.get("RTDE_SPEC_SLOW") == "1"


def examples(n: int) -> int:
    """`n` in CI and slow runs; a quarter of it (at least 10, never more than n) otherwise."""
    return n if FULL else min(n, max(10, n // 4))
