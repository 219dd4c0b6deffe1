"""Robot State (message type 16): the walk over its sub-packages, and its fast paths.

Three ways, fastest first: a message of a shape (sub-package sizes and types in order)
seen before is decoded by one generated function (`compiled.compile_shape`); otherwise
each sub-package goes to its generated decoder (`compiled.compile_part`); parts that
are unknown, shorter than their layout, or of an older layout picked by the controller
version take the general layout walk, which names what is missing. All three give the
same models (tests compare them).

A learned shape also reuses models: at 10 Hz most sub-packages (kinematics, configuration,
safety, tool communication) come with the same bytes as in the last message, and a
sub-package equal in bytes to the last one in its slot is handed out as the same frozen
model (see `compiled.CompiledShape`). A stream decoder keeps its own caches; decode_message
shares one per shape, bounded like the shapes (one model and its bytes per slot).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import Any

from rtde_spec.errors import DecodeError
from rtde_spec.metamodel.versions import Version
from rtde_spec.primary.compiled import CompiledShape, Decoder, compile_part, compile_shape
from rtde_spec.primary.fast_models import build, maker
from rtde_spec.wire.layout import Layout
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage, UnknownSubPackage

Members = dict[int, tuple[type[PrimaryPart], Layout]]
Older = dict[int, list[tuple[Version, Layout]]]  # sub-package type -> (first version not using it, layout)
PartWalk = Callable[[type[PrimaryPart], Layout, bytes, int, int], Any]  # the general layout walk

Shape = tuple[tuple[int, int], ...]  # (size, type) of each sub-package, in order
Reuse = dict[CompiledShape, list[Any]]  # a caller's own caches of sub-package models, per shape
_NONE: frozenset[int] = frozenset()
_new = object.__new__


def layout_for(older: Sequence[tuple[Version, Layout]], version: Version, newest: Layout) -> Layout:
    """The layout `version` uses: the first older one it comes before (oldest first), else the newest."""
    return next((layout for before, layout in older if version < before), newest)


class RobotStateReader:
    """Decodes Robot State bodies for one codec; learns the shapes a controller sends."""

    SHAPES_PER_SIZE = 4  # a controller sends one or two shapes (the first message adds configuration)
    SEEN_LIMIT = 256  # shapes counted before one is compiled; the count is forgotten beyond this

    def __init__(self, members: Members, older: Older, header: struct.Struct, walk: PartWalk) -> None:
        self.members, self.older, self.header, self.walk = members, older, header, walk
        self.fast: dict[int, Decoder] = {}
        for sub_type, (cls, layout) in members.items():
            decoder = compile_part(cls, layout)
            if decoder is not None:
                self.fast[sub_type] = decoder
        self._older: dict[Version, frozenset[int]] = {}
        # body size -> the shapes compiled (each checks its headers itself)
        self.shapes: dict[int, list[CompiledShape]] = {}
        self._seen: dict[Shape, int] = {}
        self._make = maker(RobotStateMessage)

    REUSE_SHAPES = 8  # caches one caller keeps (a controller sends one or two shapes)

    def decode(
        self, buf: bytes, pos: int, end: int, version: Version | None = None, reuse: Reuse | None = None
    ) -> RobotStateMessage:
        """The message's body between `pos` and `end`.

        `reuse`: the caller's own caches of the last model per sub-package (a stream
        decoder's); without one, the codec's shared cache of each shape is used. Either
        way a sub-package equal in bytes to the last one of its slot is the same (frozen)
        model object, and the result equals a decode without reuse.
        """
        older = self.older_for(version) if version is not None else _NONE
        shapes = self.shapes.get(end - pos)
        if shapes is not None and not older:
            for compiled in shapes:
                if reuse is None:
                    cache = compiled.shared
                else:
                    cache = reuse.get(compiled)  # type: ignore[assignment]
                    if cache is None:
                        if len(reuse) >= self.REUSE_SHAPES:
                            reuse.clear()
                        cache = reuse[compiled] = compiled.cache()
                subs = compiled.decode(buf, pos, cache)
                if subs is not None:
                    message = _new(RobotStateMessage)
                    message.__dict__["sub_packages"] = subs  # its own dict (as compiled.py fills them)
                    return message  # type: ignore[no-any-return]
        subs, shape = self._walk(buf, pos, end, older, version)
        if shape is not None and not older:
            self._learn(end - pos, shape)
        return self._make({"sub_packages": subs})

    def older_for(self, version: Version | None) -> frozenset[int]:
        """Sub-package types for which `version` picks an older layout: only the general walk reads those."""
        if version is None:
            return frozenset()
        found = self._older.get(version)
        if found is None:
            found = frozenset(t for t, ranges in self.older.items() if any(version < b for b, _ in ranges))
            self._older[version] = found
        return found

    def _walk(
        self, buf: bytes, pos: int, end: int, older: frozenset[int], version: Version | None
    ) -> tuple[list[Any], Shape | None]:
        """Every sub-package, one at a time; the shape when all went to their generated decoders."""
        hsize = self.header.size
        unpack = self.header.unpack_from
        fast_get = self.fast.get
        subs: list[Any] = []
        shape: list[tuple[int, int]] | None = []
        while pos < end:
            if end - pos >= hsize:
                sub_size, sub_type = unpack(buf, pos)
                stop = pos + sub_size
                if sub_size >= hsize and stop <= end:
                    fast = fast_get(sub_type)
                    part = (
                        fast(buf, pos + hsize, stop) if fast is not None and sub_type not in older else None
                    )
                    if part is not None:
                        if shape is not None:
                            shape.append((sub_size, sub_type))
                    else:  # unknown, older or shorter than its layout
                        part, shape = self._sub_package(sub_type, buf, pos, stop, version), None
                    subs.append(part)
                    pos = stop
                    continue
            self._bad_header(buf, pos, end)
        return subs, tuple(shape) if shape else None

    def _learn(self, size: int, shape: Shape) -> None:
        """Compile a decoder for a shape the second time it is seen (a one-off costs nothing)."""
        compiled = self.shapes.setdefault(size, [])
        if len(compiled) >= self.SHAPES_PER_SIZE:
            return
        seen = self._seen.get(shape, 0) + 1
        if len(self._seen) >= self.SEEN_LIMIT:
            self._seen.clear()
        self._seen[shape] = seen
        if seen < 2:
            return
        compiled_shape = compile_shape([(*self.members[t], s) for s, t in shape], self.header)
        if compiled_shape is None:
            return
        compiled.append(compiled_shape)
        self._seen.pop(shape, None)  # (another thread may have compiled it too)

    def _sub_package(self, sub_type: int, buf: bytes, pos: int, stop: int, version: Version | None) -> Any:
        """A sub-package the generated decoders do not take: unknown, older or shorter."""
        member = self.members.get(sub_type)
        if member is None:
            return build(UnknownSubPackage, {"type": sub_type, "size": stop - pos, "raw": buf[pos:stop]})
        cls, layout = member
        if version is not None:
            layout = layout_for(self.older.get(sub_type, ()), version, layout)
        return self.walk(cls, layout, buf, pos + self.header.size, stop)

    def _bad_header(self, buf: bytes, pos: int, end: int) -> None:
        """Raise what is wrong with the sub-package header at `pos`."""
        hsize = self.header.size
        if end - pos < hsize:
            raise DecodeError(
                "sub-package header cut off by the end of the message",
                package="robot_state",
                field="size",
                offset=pos,
                expected=f"{hsize} bytes",
                actual=f"{end - pos} bytes",
            )
        sub_size = self.header.unpack_from(buf, pos)[0]
        raise DecodeError(
            "sub-package size is smaller than its header"
            if sub_size < hsize
            else "sub-package size runs past the end of the message",
            package="robot_state",
            field="size",
            offset=pos,
            expected=f"{hsize}..{end - pos}",
            actual=sub_size,
        )
