"""Which RTDE protocol version is in force: the one rule every decoder and the transport share.

The controller speaks protocol 1 until it accepts a version request; from then on
both sides use the requested version. A one-sided stream sees only half of the
exchange, so the missing half is inferred: a client's request with no reply in
view is taken as accepted, and an accepted reply with no request in view means
the newest version the spec knows.
"""

from __future__ import annotations

from dataclasses import dataclass

from rtde_spec._generated.constants import RTDE_PROTOCOLS

INITIAL_VERSION = 1


@dataclass
class ProtocolState:
    version: int = INITIAL_VERSION
    requested: int | None = None
    one_sided: bool = False  # True when only one sender's packages are seen

    def on_request(self, version: int) -> None:
        """The client asked for `version` (a 'V' request)."""
        self.requested = version
        if self.one_sided and version in RTDE_PROTOCOLS:
            self.version = version

    def on_reply(self, accepted: bool) -> None:
        """The controller answered the version request."""
        if not accepted:
            self.requested = None
            return
        if self.requested in RTDE_PROTOCOLS:
            assert self.requested is not None
            self.version = self.requested
        elif self.one_sided:
            self.version = max(RTDE_PROTOCOLS)
        self.requested = None
