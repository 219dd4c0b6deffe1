"""Decode real-time messages (port 30003): one message, or a byte stream of them.

Values come out as the controller sends them, already in SI units (rad, rad/s, m, s, A,
V): the interface sends doubles and the spec gives each its unit; modes and bit fields
(doubles holding whole numbers) come out as ints. A message longer than its version's
layout (newer firmware appends fields) decodes the known prefix and says how many bytes
were left (`extra_bytes`); a shorter one decodes as the older layout of its size and
names the fields it lacks (`missing`); `strict=True` makes either an error.
"""

from __future__ import annotations

from typing import Any

from rtde_spec.errors import DecodeError, RtdeSpecError
from rtde_spec.metamodel.versions import Version
from rtde_spec.realtime.layout import (
    HEADER,
    PACKAGE,
    RealtimeLayout,
    check_size,
    known_sizes,
    layout_for,
    layout_for_size,
)
from rtde_spec.wire.framing import as_bytes


def decode(
    data: bytes | bytearray | memoryview, version: str | Version | None = None, strict: bool = False
) -> dict[str, Any]:
    """One whole real-time message (size field first) -> {field: value}.

    `version` picks the layout the controller sends; without it the message size does.
    """
    if isinstance(data, (str, int)):  # "message cut short" for hex text; a TypeError after
        as_bytes(data, "decode")
    if len(data) < HEADER.size:
        raise DecodeError(
            "message cut short", package=PACKAGE, offset=0, expected="4 bytes", actual=len(data)
        )
    (size,) = HEADER.unpack_from(data, 0)
    check_size(size, len(data))
    if len(data) > size:  # a second message, or part of one: not to be dropped unsaid
        raise DecodeError(
            f"{len(data) - size} bytes after the message (RealtimeStream decodes a stream of them)",
            package=PACKAGE, offset=size, expected=f"{size} bytes", actual=f"{len(data)} bytes",
        )  # fmt: skip
    layout = _layout(size, version, strict)
    out = layout.decode(data)
    if size > layout.size:
        out["extra_bytes"] = size - layout.size
    if version is not None:
        wanted = layout_for(version)
        if wanted is not layout:
            out["missing"] = wanted.names[len(layout.names) :]
    return out


def _layout(size: int, version: str | Version | None, strict: bool) -> RealtimeLayout:
    if version is not None:
        wanted = layout_for(version)
        if size == wanted.size:
            return wanted
        if strict:
            raise DecodeError(
                f"not the size controller {version} sends", package=PACKAGE, field="message_size",
                offset=0, expected=wanted.size, actual=size,
            )  # fmt: skip
        if size > wanted.size:
            return wanted
        older = layout_for_size(size)
        if older is not None:
            return older
        raise DecodeError(
            f"shorter than controller {version} sends, and no older layout is that size",
            package=PACKAGE, field="message_size", offset=0, expected=wanted.size, actual=size,
        )  # fmt: skip
    exact = layout_for_size(size)
    if exact is not None:
        return exact
    shorter = [s for s in known_sizes() if s < size]
    if strict or not shorter:
        raise DecodeError(
            "no layout of the spec is this size", package=PACKAGE, field="message_size", offset=0,
            expected=" or ".join(map(str, known_sizes())), actual=size,
        )  # fmt: skip
    found = layout_for_size(shorter[-1])
    assert found is not None
    return found


class RealtimeStream:
    """Cuts a TCP byte stream from port 30003 into decoded messages.

    `feed(chunk)` returns the messages completed by the chunk. A message whose body does
    not decode is skipped and kept in `errors` (its offset and number in the stream); a
    size field no message can have means the stream is lost: DecodeError, nothing buffered.
    """

    def __init__(self, version: str | Version | None = None, strict: bool = False) -> None:
        self.version, self.strict = version, strict
        self.buffer = bytearray()
        self.offset = 0  # stream offset of buffer[0]
        self.count = 0
        self.errors: list[RtdeSpecError] = []

    def feed(self, chunk: bytes | bytearray | memoryview) -> list[dict[str, Any]]:
        try:
            self.buffer += chunk
        except TypeError:  # "can't concat str to bytearray"
            as_bytes(chunk, "feed")
            raise
        out: list[dict[str, Any]] = []
        buf, at = self.buffer, 0
        while len(buf) - at >= HEADER.size:
            (size,) = HEADER.unpack_from(buf, at)
            try:
                check_size(size)
            except DecodeError as exc:
                del buf[:at]
                self.offset += at
                raise exc.in_stream(self.offset, self.count + 1) from None
            if len(buf) - at < size:
                break
            self.count += 1
            try:
                out.append(decode(memoryview(buf)[at : at + size], self.version, self.strict))
            except DecodeError as exc:
                self.errors.append(exc.in_stream(self.offset + at, self.count))
            at += size
        del buf[:at]
        self.offset += at
        return out

    @property
    def pending(self) -> int:
        """Bytes held that make no whole message yet."""
        return len(self.buffer)
