"""Controller software versions ("5.12.2", "10.11.0", "5.15.0.0") and their ordering."""

from __future__ import annotations

import re
from functools import total_ordering

from rtde_spec.errors import VersionStringError

_VERSION_RE = re.compile(r"^(\d+)\.(\d+)(?:\.(\d+))?(?:\.(\d+))?$")


@total_ordering
class Version:
    """A dotted version; a missing bugfix counts as 0 and the build number is ignored."""

    __slots__ = ("bugfix", "build", "major", "minor")

    def __init__(self, major: int, minor: int = 0, bugfix: int = 0, build: int | None = None):
        self.major, self.minor, self.bugfix, self.build = major, minor, bugfix, build

    @classmethod
    def parse(cls, text: str | Version) -> Version:
        """Parse "X.Y[.Z[.B]]"; raise VersionStringError (a ValueError) naming the text otherwise."""
        if isinstance(text, Version):
            return text
        match = _VERSION_RE.match(str(text).strip())
        if not match:
            raise VersionStringError(f"bad version string {text!r}: expected MAJOR.MINOR.BUGFIX")
        major, minor, bugfix, build = match.groups()
        return cls(int(major), int(minor), int(bugfix or 0), int(build) if build else None)

    @property
    def key(self) -> tuple[int, int, int]:
        return (self.major, self.minor, self.bugfix)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Version) and self.key == other.key

    def __lt__(self, other: Version) -> bool:
        return self.key < other.key

    def __hash__(self) -> int:
        return hash(self.key)

    def __str__(self) -> str:
        return f"{self.major}.{self.minor}.{self.bugfix}"

    def __repr__(self) -> str:
        return f"Version('{self}')"
