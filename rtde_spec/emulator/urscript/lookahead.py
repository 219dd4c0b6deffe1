"""What a motion blends into: the controller's look-ahead past statements that cannot wait."""

from __future__ import annotations

from rtde_spec.emulator.urscript import calls as script_calls
from rtde_spec.emulator.urscript.nodes import Stmt


def blends_into_move(stmt: Stmt | None) -> bool:
    return stmt is not None and stmt.kind == "call" and stmt.name in script_calls.MOVES


LOOK_AHEAD = 16  # statements that cannot wait passed over to find the next move (a blend's look-ahead)


def next_waiting(body: list[Stmt], start: int) -> Stmt | None:
    """The first statement from `start` on that may wait (a move, sync, a user function that
    waits): the controller runs the ones before it while it looks ahead to the next motion, so a
    blended move blends into a move after them (ur_rtde's paths put `signal_async_progress(i)`
    between their waypoints, PolyScope a `$ N "Waypoint"` label; the arm stopped at each)."""
    for k in range(start, min(len(body), start + LOOK_AHEAD)):  # no slice: this runs at every wait
        stmt = body[k]
        expr = stmt.expr
        if stmt.kind == "label" or (stmt.kind in ("assign", "call") and expr is not None and not expr.user
                                    and expr.kind != "run"):  # fmt: skip
            continue
        return stmt
    return None
