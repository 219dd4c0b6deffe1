"""Why decoded primary values may be wrong for the controller that sent them.

A stream decoder knows the controller version from the Version message; these checks
compare it with the spec's product lines and with the fields' `since` versions, so values
are never shown as decoded when the spec visibly does not describe that firmware.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from rtde_spec._generated.constants import PRODUCT_LINES
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

if TYPE_CHECKING:
    from rtde_spec.metamodel.versions import Version


class CodecFacts(Protocol):
    """What these checks read of `codec.PrimaryCodec`."""

    field_since: dict[tuple[str, str], dict[str, Version]]  # (member, field) -> first version per line
    families: dict[int, Any]  # type -> its family: members and older layouts


def _unexpected_missing(codec: CodecFacts, version: Version | None, parts: list[Any]) -> list[str]:
    """Missing fields that the controller's version should have sent (by the fields' `since`)."""
    if version is None:
        return []
    line = next((name for name, majors in PRODUCT_LINES.items() if version.major in majors), None)
    if line is None:
        return []  # outside the product lines: reported on its own
    out = []
    for part in parts:
        for name in getattr(part, "missing", ()):
            since = codec.field_since.get((part.NAME, name))
            expected = since is not None and (line not in since or version < since[line])
            if not expected:
                out.append(f"{part.NAME}.{name}")
    return out


def _older_names(codec: CodecFacts, version: Version | None) -> set[str]:
    """The members `version` is decoded with an older layout of (none when it is unknown)."""
    if version is None:
        return set()
    return {
        m.NAME
        for fam in codec.families.values()
        for t, (m, _) in fam.members.items()
        if any(version < before for before, _ in fam.older.get(t, []))
    }


def warnings_for(codec: CodecFacts, version: Version | None, message: Any) -> list[str]:
    """Why this message's values may be wrong: an unknown controller line, or layouts that disagree.

    Shown with each message, so values are never presented as decoded when the
    spec visibly does not describe the firmware that sent them.
    """
    out = []
    if version is not None and not any(version.major in majors for majors in PRODUCT_LINES.values()):
        lines = ", ".join(f"{name} {'/'.join(map(str, m))}.x" for name, m in PRODUCT_LINES.items())
        used = sorted(_older_names(codec, version))
        known = f" (older layouts from public sources used for {', '.join(used)})" if used else ""
        out.append(
            f"controller {version} is outside the spec's product lines ({lines}){known}; "
            "other layouts are not described for it, so values may be wrong"
        )
    parts = message.sub_packages if isinstance(message, RobotStateMessage) else [message]
    unexpected = _unexpected_missing(codec, version, parts)
    if unexpected:
        names = ", ".join(unexpected)
        out.append(f"missing on controller {version}, which the spec says sends them: {names}")
    if isinstance(message, RobotStateMessage):
        # a part read with an older layout lacks the current fields and may carry bytes after its
        # documented end (the spec's `older` says which): neither is a disagreement
        odd = [s for s in message.sub_packages if isinstance(s, PrimaryPart) and (s.missing or s.extra)]
        older = _older_names(codec, version) if odd else set()
        shorter = [s.NAME for s in odd if s.missing and s.NAME not in older]
        longer = [s.NAME for s in odd if s.extra and s.NAME not in older]
        if shorter and longer:
            out.append(
                "layouts disagree: some sub-packages are shorter than the spec "
                f"({', '.join(shorter)}) and others longer ({', '.join(longer)}); "
                "no single firmware sends that, so these values may be wrong"
            )
    return out
