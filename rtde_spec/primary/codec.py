"""bytes <-> primary/secondary interface messages, built once from the spec.

decode_message takes one whole message (u32 size, u8 type, body); the stream
decoder frames a byte stream across arbitrary read boundaries and keeps the
controller version the Version message announces. Unknown message types,
sub-package types and sub-message types are kept with their bytes.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cache, partial
from typing import TYPE_CHECKING, Any

from rtde_spec._generated import primary_models as gen
from rtde_spec._generated.constants import PRIMARY_BYTE_ORDER as ORDER
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.metamodel.versions import Version
from rtde_spec.primary.compiled import Decoder
from rtde_spec.primary.compiled_tagged import family_decoder
from rtde_spec.primary.families import FamilyView, PrimaryView, primary_view
from rtde_spec.primary.fast_models import build, with_groups
from rtde_spec.primary.robot_state import Reuse, RobotStateReader, layout_for
from rtde_spec.primary.version_warnings import warnings_for
from rtde_spec.wire.framing import PackageFramer, Skipped, as_bytes, check_header
from rtde_spec.wire.layout import Layout
from rtde_spec.wire.primary_base import (
    OpaqueMessage,
    PrimaryModel,
    PrimaryPart,
    RobotStateMessage,
    UnknownMember,
    UnknownMessage,
    UnknownSubPackage,
)
from rtde_spec.wire.primary_values import ValueTable

if TYPE_CHECKING:
    from rtde_spec.metamodel.schema import Spec

PrimaryMessage = RobotStateMessage | PrimaryPart | OpaqueMessage | UnknownMessage | UnknownMember


@dataclass
class _Family:
    spec: FamilyView
    prefix: Layout | None
    members: dict[int, tuple[type[PrimaryPart], Layout]] = field(default_factory=dict)
    older: dict[int, list[tuple[Version, Layout]]] = field(default_factory=dict)  # oldest range first
    fast: dict[int, Decoder] = field(default_factory=dict)  # tag -> generated decoder (compiled_tagged.py)
    direct: Decoder | None = None  # a tagged member through its generated decoder, or None


class PrimaryCodec:
    """Compiled layouts of every message family of a spec.

    Given no spec, the built-in one, read from the generated data without the meta-model.
    """

    def __init__(self, spec: Spec | PrimaryView | None = None) -> None:
        if spec is None:
            from rtde_spec._generated.spec_data import SPEC

            pf = primary_view(SPEC)
        elif isinstance(spec, PrimaryView):
            pf = spec
        else:  # a validated spec: its data, as codegen writes it
            pf = primary_view(spec.model_dump(mode="json", exclude_defaults=True))
        self.prims = prims = pf.primitives
        codes = pf.codes["GlobalVariableType"]
        self.values = ValueTable(list(pf.value_types), codes, prims, pf.value_separator)
        self.header = struct.Struct(ORDER + "".join(prims[h.type].struct for h in pf.header))
        self.sub_header = struct.Struct(ORDER + "".join(prims[h.type].struct for h in pf.subpackage_header))
        self.max_size = pf.max_message_bytes
        # bytes of the size field a message starts with (what a stream is framed by)
        self.size_bytes = prims[next(h.type for h in pf.header if h.name == "size")].size
        self.families: dict[int, _Family] = {}
        self.by_class: dict[type[PrimaryPart], tuple[_Family, Layout]] = {}
        self.member_types: dict[type[PrimaryPart], int] = {}  # for the older layouts of a member
        # (member, field) -> first version per product line, for fields added after their member
        self.field_since: dict[tuple[str, str], dict[str, Version]] = {}
        for fam in pf.families:
            prefix = Layout(fam.prefix, prims, self.values) if fam.prefix else None
            entry = _Family(fam, prefix)
            for member in fam.members:
                cls = gen.MEMBERS[(fam.name, member.type)]
                layout = Layout(member.fields, prims, self.values)
                entry.members[member.type] = (cls, layout)
                self.by_class[cls] = (entry, layout)
                self.member_types[cls] = member.type
                for fld in member.fields:
                    if fld.since:
                        since = {line: Version.parse(v) for line, v in fld.since.items()}
                        self.field_since[(member.name, fld.name)] = since
                if member.older:
                    ranges = [
                        (Version.parse(o.before), Layout(o.fields, prims, self.values)) for o in member.older
                    ]
                    entry.older[member.type] = sorted(ranges, key=lambda r: r[0])
            self.families[fam.type] = entry
            if prefix is not None and fam.tag:  # the members' generated decoders
                found = family_decoder(entry.members, entry.older, prefix, fam.tag, self.values)
                entry.direct, entry.fast = found
        # Robot State: generated decoders per sub-package and per message shape (robot_state.py)
        self.state_type = gen.FAMILY_TYPES["robot_state"]
        state = self.families[self.state_type]
        walk = partial(self._part, prefix={})
        self.robot_state = RobotStateReader(state.members, state.older, self.sub_header, walk)

    # --- decoding -----------------------------------------------------------

    def decode_message(
        self,
        data: bytes | bytearray | memoryview,
        *,
        strict: bool = True,
        version: Version | None = None,
        reuse: Reuse | None = None,
    ) -> PrimaryMessage:
        """One whole message; with strict=False bytes after it are ignored.

        `version` (from the Version message) picks the spec's older layouts where a
        sub-package has them. `reuse`: a caller's own cache of Robot State sub-package
        models (`{}` to start one; a stream decoder keeps one), else the codec's shared one.
        """
        buf = data if type(data) is bytes else as_bytes(data, "decode_message")
        hsize = self.header.size
        size, mtype = self.header.unpack_from(buf) if len(buf) >= hsize else (0, 0)
        if not (hsize <= size <= self.max_size and (size == len(buf) or (not strict and size < len(buf)))):
            size, mtype = check_header(  # says what is wrong
                buf,
                self.header,
                what="message",
                max_size=self.max_size,
                strict=strict,
                hint="; use PrimaryStreamDecoder for several",
            )
        if mtype == self.state_type:  # most of a stream: Robot State, ten times a second
            return self.robot_state.decode(buf, hsize, size, version, reuse)
        fam = self.families.get(mtype)
        if fam is None:
            return build(UnknownMessage, {"type": mtype, "size": size, "raw": buf[:size]})
        if fam.direct is not None:  # a tagged member's generated decoder
            made = fam.direct(buf, hsize, size)
            if made is not None:
                return made  # type: ignore[no-any-return]
        layout = fam.spec.layout
        if layout == "opaque":
            return build(OpaqueMessage, {"family": fam.spec.name, "type": mtype, "raw": buf[hsize:size]})
        if layout == "subpackages":
            return self.robot_state.decode(buf, hsize, size, version, reuse)
        return self._tagged(fam, buf, hsize, size)

    def _tagged(self, fam: _Family, buf: bytes, pos: int, end: int) -> PrimaryMessage:
        assert fam.prefix is not None
        prefix, missing, pos = fam.prefix.decode(buf, pos, end)
        if missing:
            raise DecodeError(
                f"message ends inside its prefix ({', '.join(missing)} missing)",
                package=fam.spec.name,
                field=missing[0],
                offset=pos,
            )
        tag = prefix[fam.spec.tag or ""]
        member = fam.members.get(tag)
        if member is None:
            values = {"family": fam.spec.name, "type": tag, "prefix": prefix, "raw": buf[pos:end]}
            return build(UnknownMember, values)
        cls, layout = member
        return self._part(cls, layout, buf, pos, end, prefix)

    def _part(
        self, cls: type[PrimaryPart], layout: Layout, buf: bytes, pos: int, end: int, prefix: dict[str, Any]
    ) -> PrimaryPart:
        try:
            values, missing, stop = layout.decode(buf, pos, end)
        except DecodeError as exc:
            raise exc.relocated(package=cls.NAME) from None
        if prefix:
            values.update(prefix)
        full = self.by_class[cls][1]
        if full is not layout:  # an older layout: the current fields it lacks are missing too
            missing = [n for n in full.names if n not in values and n not in missing] + missing
        for name in missing:
            values[name] = None
        values["missing"] = tuple(missing)
        values["extra"] = buf[stop:end]
        if layout.group_fields:
            with_groups(layout, values)
        return build(cls, values)

    # --- encoding -----------------------------------------------------------

    def encode_part_body(self, part: PrimaryPart, version: Version | None = None) -> bytes:
        """The part's body in the layout `version` uses (the newest without one), as decoding picks it."""
        fam, layout = self.by_class[type(part)]
        if version is not None:
            layout = layout_for(fam.older.get(self.member_types[type(part)], ()), version, layout)
        dumped = part.model_dump()
        body = layout.encode(dumped)
        if fam.prefix is not None:
            body = fam.prefix.encode(dumped) + body
        return body + part.extra

    def encode(self, message: PrimaryModel, version: Version | None = None) -> bytes:
        """A whole message from a model (a tagged member, Robot State, unknown or opaque), in the
        layouts of controller `version` (as `decode_message(version=...)` reads them; None: the
        newest). A part decoded with an older layout is encoded back with the same version."""
        if isinstance(message, UnknownMessage):
            return message.raw
        if isinstance(message, RobotStateMessage):
            body = b"".join(self._encode_sub(s, version) for s in message.sub_packages)
            mtype = gen.FAMILY_TYPES["robot_state"]
        elif isinstance(message, OpaqueMessage):
            body, mtype = message.raw, message.type
        elif isinstance(message, UnknownMember):
            fam = self.families[gen.FAMILY_TYPES[message.family]]
            assert fam.prefix is not None
            body, mtype = fam.prefix.encode(message.prefix) + message.raw, fam.spec.type
        elif isinstance(message, PrimaryPart) and type(message) in self.by_class:
            fam, _ = self.by_class[type(message)]
            if fam.spec.layout == "subpackages":
                return self.encode(RobotStateMessage(sub_packages=[message]), version)
            body, mtype = self.encode_part_body(message, version), fam.spec.type
        else:
            raise EncodeError(f"not a primary-interface message: {type(message).__name__}")
        return self._frame(self.header, body, mtype, "message")

    def _encode_sub(self, sub: Any, version: Version | None = None) -> bytes:
        if isinstance(sub, UnknownSubPackage):
            return sub.raw
        if (
            not isinstance(sub, PrimaryPart)
            or self.by_class.get(type(sub), (None,))[0] is not self.families[gen.FAMILY_TYPES["robot_state"]]
        ):
            raise EncodeError(f"not a Robot State sub-package: {type(sub).__name__}", package="robot_state")
        return self._frame(self.sub_header, self.encode_part_body(sub, version), sub.TYPE, sub.NAME)

    def _frame(self, header: struct.Struct, body: bytes, mtype: int, name: str) -> bytes:
        size = header.size + len(body)
        if size > self.max_size:
            raise EncodeError(
                "message too large",
                package=name,
                expected=f"<= {self.max_size} bytes",
                actual=f"{size} bytes",
            )
        return header.pack(size, mtype) + body


@cache
def default_codec() -> PrimaryCodec:
    return PrimaryCodec()


def decode_message(
    data: bytes | bytearray | memoryview, *, strict: bool = True, version: Version | str | None = None
) -> PrimaryMessage:
    """One whole primary/secondary message (header included).

    `version` ("1.8", "3.2.0", a Version): the controller that sent it, when its Version message
    is not at hand (a dump of one message, a stream joined late); it picks the spec's older
    layouts as a stream decoder's Version message does. None: the newest layouts.
    """
    known = Version.parse(version) if version is not None else None
    return default_codec().decode_message(data, strict=strict, version=known)


def encode_message(message: PrimaryModel, *, version: Version | str | None = None) -> bytes:
    """One whole message, in the layouts of controller `version` ("1.8", a Version; None: the
    newest): a message decoded with `version` encodes back to its bytes with the same one."""
    known = Version.parse(version) if version is not None else None
    return default_codec().encode(message, known)


def announced_version(message: PrimaryMessage) -> Version | None:
    """The controller version a Version message announces (None for any other message): the
    context that picks older layouts for what follows on the same connection."""
    if not isinstance(message, gen.VersionMessage) or message.major_version is None:
        return None
    return Version(
        message.major_version, message.minor_version or 0, message.bugfix_version or 0, message.build_number
    )


class PrimaryStreamDecoder:
    """Frames a TCP byte stream into messages and decodes them in order.

    The Version message (the first one on every port) sets `version`, the
    controller version context for what follows; `version` given here stands for it
    in a stream joined late (a Version message in the stream still wins). A size that cannot be framed
    raises after the messages before it are decoded (in `decoded`); with
    `skip_errors`, a framed message that does not decode is counted in `skipped`
    and the stream goes on.
    """

    def __init__(
        self,
        codec: PrimaryCodec | None = None,
        *,
        skip_errors: bool = False,
        version: Version | str | None = None,
    ) -> None:
        self.codec = codec or default_codec()
        self.skip_errors = skip_errors
        self.skipped = Skipped()
        self.framer = PackageFramer(
            size_bytes=struct.calcsize(ORDER + self.codec.header.format[1]),
            header_size=self.codec.header.size,
            max_size=self.codec.max_size,
        )
        self.version: Version | None = Version.parse(version) if version is not None else None
        self.announced = False  # a Version message in the stream set `version`
        self.count = 0
        self.decoded: list[tuple[int, PrimaryMessage]] = []  # of the last feed, up to an error
        self.reuse: Reuse = {}  # the last model of each Robot State sub-package (robot_state.py)

    def feed(self, data: bytes | bytearray | memoryview) -> list[tuple[int, PrimaryMessage]]:
        out: list[tuple[int, PrimaryMessage]] = []
        self.decoded = out
        codec = self.codec
        if type(data) is bytes and len(data) >= codec.header.size:  # one whole message, nothing held:
            size, mtype = codec.header.unpack_from(data)  # what a 10 Hz client's read usually is
            if size == len(data) and size <= codec.max_size and mtype == codec.state_type:
                offset = self.framer.take_whole(size)  # framed as the framer would (it counts it)
                if offset is not None:
                    self._decode_state(out, offset, data, size)
                    return out
        try:
            framed = self.framer.feed(data)
        except DecodeError:  # an unusable size: the messages before it still decode, then it is raised
            self._decode_into(out, self.framer.salvaged)
            raise
        self._decode_into(out, framed)
        return out

    def _decode_state(self, out: list[tuple[int, PrimaryMessage]], at: int, raw: bytes, size: int) -> None:
        """A whole Robot State message, as _decode_into decodes it, without its general steps."""
        self.count += 1
        offset, codec = at, self.codec
        try:
            message = codec.robot_state.decode(raw, codec.header.size, size, self.version, self.reuse)
        except DecodeError as exc:
            if not self.skip_errors:
                raise exc.in_stream(offset, self.count) from None
            self.skipped.add(offset, size, str(exc.in_stream(offset, self.count)))
            return
        out.append((offset, message))

    def _decode_into(self, out: list[tuple[int, PrimaryMessage]], framed: list[tuple[int, bytes]]) -> None:
        for offset, raw in framed:
            self.count += 1
            try:
                message = self.codec.decode_message(raw, version=self.version, reuse=self.reuse)
            except DecodeError as exc:
                if not self.skip_errors:
                    raise exc.in_stream(offset, self.count) from None
                self.skipped.add(offset, len(raw), str(exc.in_stream(offset, self.count)))
                continue
            announced = announced_version(message)
            if announced is not None:
                self.version, self.announced = announced, True
            out.append((offset, message))

    def warnings_for(self, message: PrimaryMessage) -> list[str]:
        """Why this message's values may be wrong (`version_warnings.py`), shown with each message."""
        return warnings_for(self.codec, self.version, message)

    @property
    def unframed(self) -> int:
        """Bytes held that are not (yet) a message: after a framing fault, those from the fault on."""
        return self.framer.pending

    def close(self) -> None:
        self.framer.close()


def decode_stream(data: bytes | bytearray | memoryview) -> Iterator[tuple[int, PrimaryMessage]]:
    """(offset, message) for every message of a complete buffer."""
    decoder = PrimaryStreamDecoder()
    yield from decoder.feed(data)
    decoder.close()
