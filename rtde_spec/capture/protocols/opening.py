"""What a connection's first bytes from the server say it speaks: the capture's content
recognition (a port the spec does not name) and a port's misfit (another interface's bytes)."""

from __future__ import annotations

from functools import cache


@cache
def _primary_opening() -> tuple[int, int, int]:
    """(message type, tag offset, tag value) of the version message a primary server sends first."""
    from rtde_spec.primary.codec import default_codec

    codec = default_codec()
    prims = codec.prims
    for family in codec.families.values():
        version = next((m for m in family.spec.members if m.name == "version_message"), None)
        if version is None or family.spec.tag is None:
            continue
        at = codec.header.size
        for fld in family.spec.prefix:
            if fld.name == family.spec.tag:
                return family.spec.type, at, version.type
            at += prims[fld.type].size * (fld.count or 1)
    raise LookupError("the spec has no primary version message")


def content_kind(payload: bytes) -> str | None:
    """A protocol recognised from a connection's first bytes, sent by the server (None: unknown)."""
    from rtde_spec.realtime import known_sizes

    if len(payload) >= 4 and int.from_bytes(payload[:4], "big") in known_sizes():
        return "realtime"
    mtype, tag_at, tag = _primary_opening()
    if len(payload) > tag_at and payload[4] == mtype and payload[tag_at] == tag:
        size = int.from_bytes(payload[:4], "big")
        if tag_at < size <= 4096:
            return "primary"
    return None
