"""What every client connects to, checked before it connects: one rule for the RTDE and the
primary clients (port 70000 reached port 4464; a time-out of None, -1 or "5" failed inside the
socket module)."""

from __future__ import annotations

import math

from rtde_spec.errors import UsageError


def check_endpoint(host: str, port: int, timeout: float) -> None:
    """UsageError naming `host:port` for a port outside 1..65535 or a time-out that is no positive
    number of seconds."""
    where = f"{host}:{port}"
    if isinstance(port, int) and not 0 < port <= 65535:
        raise UsageError(f"port must be 1..65535, not {port}", subject=where)
    number = isinstance(timeout, (int, float)) and not isinstance(timeout, bool)
    if not number or not 0 < timeout or math.isinf(timeout):
        raise UsageError(f"timeout must be a number of seconds above 0, not {timeout!r}", subject=where)
