"""One generated function per tagged message (robot messages, program state): straight-line decoding.

The general walk decodes a text or version message through a dict per layout, a call per
field and a regroup; a message of a few dozen bytes cost 3-13 µs, most of it steps. Here
each member gets the code `compiled.py` gives a Robot State sub-package: the prefix and the
member's leading fixed fields in one unpack, a slice per string (its length prefix read by
a struct), a branch per switch case, a loop for entries repeated to the end, and the model's
own `__dict__` filled key by key, in the order the general walk fills it.

Whatever is not plain goes back to the general walk, which names what is wrong: the
generated function returns None for a part shorter than its layout, a length prefix past
the end, or an entry cut off; `decode_all` errors of typed values are handed back the same
way. Members with optional groups or scaled values are not compiled.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from rtde_spec._generated import primary_models as gen
from rtde_spec.errors import DecodeError
from rtde_spec.primary.compiled import Decoder, NotFixed, Source, entries_of
from rtde_spec.wire.layout import Layout, _text

if TYPE_CHECKING:
    from rtde_spec.wire.fields import FieldLike
    from rtde_spec.wire.primary_values import ValueTable


def _length(src: Source, layout: Layout, prefix_type: str) -> tuple[str, int]:
    """The unpack function of a length prefix (a name in `src.env`) and its size."""
    prim = layout.prims[prefix_type]
    return src.name("L", struct.Struct(layout.order + prim.struct).unpack_from), prim.size


def _prefixed(src: Source, layout: Layout, prefix_type: str, raw: str) -> None:
    """Statements reading a length-prefixed run of bytes at p into `raw` (None when it does not fit)."""
    unpack, size = _length(src, layout, prefix_type)
    src.add(
        f"if end - p < {size}:",
        "    return None",
        f"(n,) = {unpack}(buf, p)",
        f"q = p + {size}",
        "if n < 0 or end - q < n:",
        "    return None",
        f"{raw} = buf[q:q + n]",
        "p = q + n",
    )


def _text_of(src: Source, raw: str, fmt: str | None) -> str:
    if fmt is None:
        return f"{raw}.decode('utf-8', 'surrogateescape')"
    return f"{src.name('T', _text)}({raw}, {fmt!r})"


def _string(src: Source, layout: Layout, fld: FieldLike) -> str:
    """Statements reading a string or bytes field; the expression of its value."""
    raw = src.name("r")
    if fld.length == "rest" and fld.format == "lines":  # up to the last newline; a tail stays extra
        src.add("k = buf.rfind(b'\\n', p, end) + 1", f"{raw} = buf[p:k] if k else b''", "p = k or p")
    elif fld.length == "rest":
        src.add(f"{raw} = buf[p:end]", "p = end")
    elif fld.fallback == "rest":  # peers send it without the prefix: it holds the rest either way
        unpack, size = _length(src, layout, fld.length or "")
        src.add(
            f"if end - p < {size}:",
            "    return None",
            f"(n,) = {unpack}(buf, p)",
            f"{raw} = buf[p + {size}:end] if n == end - p - {size} else buf[p:end]",
            "p = end",
        )
    else:
        _prefixed(src, layout, fld.length or "", raw)
    return _text_of(src, raw, fld.format) if fld.kind == "string" else raw


def _switch(src: Source, layout: Layout, fld: FieldLike, entries: list[str]) -> str:
    """Statements reading the case the selector picks (None for an unknown one); its variable."""
    selector = next(e.split(": ", 1)[1] for e in entries if e.startswith(repr(fld.switch) + ":"))
    var, by_type = src.name("s"), dict[Any, list[int]]()
    for value, case in (fld.cases or {}).items():
        by_type.setdefault(case if isinstance(case, str) else ("text", case.length), []).append(value)
    src.add(f"sel = {selector}")
    word = "if"
    for case, values in by_type.items():
        src.add(f"{word} sel in {tuple(values)!r}:")
        src.indent += "    "
        if isinstance(case, tuple):
            raw = src.name("r")
            _prefixed(src, layout, case[1] or "", raw)
            src.add(f"{var} = {raw}.decode('utf-8', 'surrogateescape')")
        else:
            step = struct.Struct(layout.order + layout.prims[case].struct)
            src.add(
                f"if end - p < {step.size}:",
                "    return None",
                f"({var},) = {src.name('U', step.unpack_from)}(buf, p)",
                f"p += {step.size}",
            )
        src.indent = src.indent[:-4]
        word = "elif"
    src.add("else:" if by_type else "if True:", f"    {var} = None")
    return var


def _entries(src: Source, layout: Layout, fields: list[Any], values: ValueTable | None) -> list[str]:
    """'name: expression' entries of every field, in order, with the statements reading them."""

    def other(fld: FieldLike, entries: list[str]) -> str:
        if fld.kind in ("string", "bytes"):
            return _string(src, layout, fld)
        if fld.kind == "switch":
            return _switch(src, layout, fld, entries)
        if fld.kind == "values" and values is not None:
            var = src.name("x")
            src.add(f"{var} = {src.name('V', values.decode_all)}(buf, p, end, {fld.name!r})", "p = end")
            return var
        if fld.kind == "repeat" and fld.repeat == "until_end" and fld.group is not None:
            return _until_end(src, layout, fld, values)
        raise NotFixed

    return entries_of(src, layout, fields, other)


def _until_end(src: Source, layout: Layout, fld: FieldLike, values: ValueTable | None) -> str:
    """Statements reading entries of a group to the end of the part; the variable of their list."""
    var = src.name("g")
    src.add(f"{var} = []", "while p < end:")
    src.indent += "    "
    inner = layout.groups[fld.name]
    made = src.model(gen.GROUPS[fld.group or ""], _entries(src, inner, list(inner.fields), values))
    src.add(f"{var}.append({made})")
    src.indent = src.indent[:-4]
    return var


def compile_member(
    cls: type[BaseModel], prefix: Layout, layout: Layout, values: ValueTable | None
) -> Decoder | None:
    """decode(buf, pos, end) -> the member's model from its prefix at `pos` on, or None (the
    general walk then decodes it and names what is wrong). None from compile_member: the
    layout has a field the generated code does not cover."""
    src = Source()
    src.add("p = pos")
    try:
        entries = _entries(src, layout, [*prefix.fields, *layout.fields], values)
        first = {f"{f.name!r}" for f in prefix.fields}
        own = [e for e in entries if e.split(":")[0] not in first]
        ordered = [*own, *(e for e in entries if e.split(":")[0] in first)]  # as the general walk
        part = src.model(cls, [*ordered, "'missing': ()", "'extra': buf[p:end]"])
    except NotFixed:
        return None
    body = "\n    ".join([*src.lines, f"return {part}"])
    exec(f"def decode(buf, pos, end):\n    {body}\n", src.env)
    return src.env["decode"]  # type: ignore[no-any-return]


TagReader = tuple[Callable[[bytes, int], tuple[Any, ...]], int, int]  # unpack, offset, bytes it needs


def tag_reader(prefix: Layout, tag: str) -> TagReader | None:
    """The unpack of a family's tag, its offset in the prefix and the prefix bytes up to its end;
    None when a field before it is not of fixed size."""
    offset = 0
    for fld in prefix.fields:
        if fld.kind != "value":
            return None
        prim = prefix.prims[fld.type or ""]
        if fld.name == tag and fld.count is None:
            return struct.Struct(prefix.order + prim.struct).unpack_from, offset, offset + prim.size
        offset += prim.size * (fld.count or 1)
    return None


def family_decoder(
    members: dict[int, tuple[type[Any], Layout]],
    older: dict[int, Any],
    prefix: Layout,
    tag: str,
    values: ValueTable | None,
) -> tuple[Decoder | None, dict[int, Decoder]]:
    """decode(buf, pos, end) for a tagged family: the model of the member at `pos` from its
    generated decoder, or None when there is none or it steps aside (the general walk then
    decodes the member and names what is wrong); and the members' decoders by tag. Members
    with older layouts, which a controller version picks, and members not covered are left out."""
    reader = tag_reader(prefix, tag)
    if reader is None:
        return None, {}
    fast = {}
    for tag_value, (cls, layout) in members.items():
        decoder = None if tag_value in older else compile_member(cls, prefix, layout, values)
        if decoder is not None:
            fast[tag_value] = decoder
    unpack, offset, need = reader
    get = fast.get
    one_byte = need - offset == 1 and unpack(b"\xff", 0)[0] == 255  # an unsigned byte: buf[i] reads it

    def decode(buf: bytes, pos: int, end: int) -> Any:
        if end - pos < need:
            return None
        decoder = get(buf[pos + offset] if one_byte else unpack(buf, pos + offset)[0])
        if decoder is None:
            return None
        try:
            return decoder(buf, pos, end)
        except DecodeError:  # typed values: the general walk says it with the member's name
            return None

    return decode, fast
