"""One generated function per Robot State sub-package: few unpacks, then its models.

A Robot State is ~30 frozen models (sub-packages, joints, limits). The general
layout walk costs a dict per group, a regroup pass and a function call per model;
here each sub-package gets straight-line code, built once from the same spec
layout: one unpack per fixed run (fixed groups included), a branch for a
conditional group, a slice for trailing bytes, and every model's __dict__ filled
directly, pydantic's bookkeeping slots left to `PrimaryModel.__getattr__` (as
`fast_models.maker` does, minus the call). A part shorter than its
layout returns None and the general walk names what is missing; layouts with
strings, switches or open-ended groups are not compiled.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from rtde_spec._generated import primary_models as gen
from rtde_spec.wire.layout import Layout

if TYPE_CHECKING:  # annotations only: the meta-model is not built at run time
    from rtde_spec.metamodel.schema import LayoutField

Decoder = Callable[[bytes, int, int], Any]

_SLOTS = BaseModel.__dict__  # the slot descriptors pydantic keeps per instance


class _Source:
    """Statements of one generated function, and the objects it names."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.indent = ""
        self.env: dict[str, Any] = {"_new": object.__new__, "_dict": _SLOTS["__dict__"].__set__}
        self.count = 0
        # batched: models are made all at once by two C loops at the end (see compile_shape)
        self.batched: list[tuple[str, type[BaseModel], str]] | None = None

    def name(self, prefix: str, value: Any = None) -> str:
        self.count += 1
        name = f"{prefix}{self.count}"
        if value is not None:
            self.env[name] = value
        return name

    def add(self, *lines: str) -> None:
        self.lines += [self.indent + line for line in lines]

    def model(self, cls: type[BaseModel], entries: list[str]) -> str:
        """Statements making one `cls` from 'key: expression' entries; returns its variable."""
        if set(cls.model_fields) != {e.split(":")[0].strip("'") for e in entries}:
            raise _NotFixed
        if self.batched is not None:
            var = self.name("m")
            self.batched.append((var, cls, f"{{{', '.join(entries)}}}"))
            return var
        var, name = self.name("m"), self.name("C", cls)
        self.add(
            f"{var} = _new({name})",
            f"_dict({var}, {{{', '.join(entries)}}})",
        )
        return var


class _NotFixed(Exception):
    """The layout has a part the generated code does not cover: the general path decodes it."""


def _fields(src: _Source, fields: list[LayoutField], t: str, index: int) -> tuple[list[str], int]:
    """'name: expression' entries for fixed fields read from tuple `t` at `index`."""
    entries = []
    for fld in fields:
        if fld.kind == "value":
            count = fld.count or 1
            expr = f"{t}[{index}]" if fld.count is None else f"{t}[{index}:{index + count}]"
            entries.append(f"{fld.name!r}: {expr}")
            index += count
        elif fld.kind == "repeat" and isinstance(fld.repeat, int) and fld.group is not None:
            made = []
            for _ in range(fld.repeat):
                values, index = _fields(src, fld.fields or [], t, index)
                made.append(src.model(gen.GROUPS[fld.group], values))
            entries.append(f"{fld.name!r}: ({', '.join(made)},)")
        else:
            raise _NotFixed
    return entries, index


def _unpack(src: _Source, layout: Layout, fields: list[LayoutField]) -> list[str]:
    """Statements reading one fixed run at p (None when the part is too short); its entries."""
    step = Layout(fields, layout.prims, order=layout.order)._single
    if step is None:
        raise _NotFixed
    t, unpack = src.name("t"), src.name("U", step.struct.unpack_from)
    size = step.struct.size
    src.add(f"if end - p < {size}:", "    return None", f"{t} = {unpack}(buf, p)", f"p += {size}")
    entries, _ = _fields(src, fields, t, 0)
    return entries


def _body(src: _Source, layout: Layout) -> list[str]:
    """Entries of every field: fixed runs, conditional fixed groups, a trailing rest of bytes/text."""
    entries: list[str] = []
    run: list[LayoutField] = []
    for i, fld in enumerate(layout.fields):
        if fld.kind == "value" or (fld.kind == "repeat" and isinstance(fld.repeat, int)):
            run.append(fld)
            continue
        if run:
            entries += _unpack(src, layout, run)
            run = []
        if fld.kind == "optional" and fld.group is not None:
            flag = next(e.split(": ", 1)[1] for e in entries if e.startswith(repr(fld.when) + ":"))
            var = src.name("o")
            src.add(f"if {flag}:")
            src.indent += "    "
            inner = _unpack(src, layout, fld.fields or [])
            src.add(f"{var} = {src.model(gen.GROUPS[fld.group], inner)}")
            src.indent = src.indent[:-4]
            src.add("else:", f"    {var} = None")
            entries.append(f"{fld.name!r}: {var}")
        elif fld.kind == "bytes" and fld.length == "rest" and i == len(layout.fields) - 1:
            src.add("rest = buf[p:end]", "p = end")
            entries.append(f"{fld.name!r}: rest")
        else:
            raise _NotFixed
    if run:
        entries += _unpack(src, layout, run)
    return entries


def _emit_part(src: _Source, cls: type[BaseModel], layout: Layout) -> str:
    """Statements decoding one part between `p` and `end`; returns the variable of its model."""
    entries = _body(src, layout)
    return src.model(cls, [*entries, "'missing': ()", "'extra': buf[p:end]"])


def compile_part(cls: type[BaseModel], layout: Layout) -> Decoder | None:
    """decode(buf, start, end) -> the part's model, or None when the part is shorter than its layout.

    None from compile_part itself: the layout has strings, switches or open-ended groups,
    which the general path decodes. Bytes after the layout are the part's `extra`.
    """
    src = _Source()
    src.add("p = start")
    try:
        part = _emit_part(src, cls, layout)
    except _NotFixed:
        return None
    body = "\n    ".join([*src.lines, f"return {part}"])
    exec(f"def decode(buf, start, end):\n    {body}\n", src.env)
    return src.env["decode"]  # type: ignore[no-any-return]


ShapeDecoder = Callable[[bytes, int], "list[Any] | None"]


class _Shared:
    """One struct over a whole message: the fixed runs of its parts at their offsets."""

    def __init__(self, src: _Source) -> None:
        self.runs: list[tuple[int, str]] = []  # (offset from pos, format without byte order)
        self.count = 0  # values so far
        self.order = ""
        self.var = src.name("T")

    def add(self, offset: int, fmt: struct.Struct) -> int:
        """Register a run; returns the index of its first value in the shared tuple."""
        first = self.count
        self.order = fmt.format[0]
        self.runs.append((offset, fmt.format[1:]))
        self.count += len(fmt.unpack(bytes(fmt.size)))
        return first

    def struct(self) -> struct.Struct:
        parts, at = [], 0
        for offset, fmt in self.runs:
            parts += [f"{offset - at}x", fmt]
            at = offset + struct.calcsize(self.order + fmt)
        return struct.Struct(self.order + "".join(parts))


def _merged_part(
    src: _Source, shared: _Shared, cls: type[BaseModel], layout: Layout, start: int, end: int
) -> str | None:
    """A part of fixed fields (and perhaps trailing rest-of-part bytes) read from the shared
    tuple, its extra bytes sliced at known offsets; None when it has other fields."""
    fields, rest = list(layout.fields), None
    if fields and fields[-1].kind == "bytes" and fields[-1].length == "rest":
        rest = fields.pop()
    if any(f.kind != "value" and not (f.kind == "repeat" and isinstance(f.repeat, int)) for f in fields):
        return None
    size, entries = 0, list[str]()
    if fields:
        step = Layout(fields, layout.prims, order=layout.order)._single
        if step is None:
            raise _NotFixed
        size = step.struct.size
        if end - start < size:  # shorter than its layout: the general walk names what is missing
            raise _NotFixed
        entries, _ = _fields(src, fields, shared.var, shared.add(start, step.struct))
    tail = f"buf[pos + {start + size}:pos + {end}]" if start + size < end else "b''"
    if rest is not None:
        entries.append(f"{rest.name!r}: {tail}")
        tail = "b''"
    return src.model(cls, [*entries, "'missing': ()", f"'extra': {tail}"])


def compile_shape(parts: list[tuple[type[BaseModel], Layout, int]], header_size: int) -> ShapeDecoder | None:
    """decode(buf, pos) -> the models of a run of sub-packages of exactly these (class, layout,
    size including header) at `pos`, in one function: one unpack for every fixed field of
    the message, no loop, no call per part.

    A controller sends the same sub-packages every time, so a Robot State of a shape seen
    before is decoded by straight-line code end to end. None from decode: a part with a
    conditional group is shorter than its layout (the general walk then names what is
    missing); None from compile_shape: a part is shorter than its layout, or has a
    layout the generated code does not cover.
    """
    src = _Source()
    shared = _Shared(src)
    made, offset = [], 0
    batched: list[tuple[str, type[BaseModel], str]] = []
    try:
        for cls, layout, size in parts:
            start, end = offset + header_size, offset + size
            src.batched = batched
            var = _merged_part(src, shared, cls, layout, start, end)
            src.batched = None
            if var is None:  # a conditional group: this part reads on its own
                src.add(f"p = pos + {start}", f"end = pos + {end}")
                var = _emit_part(src, cls, layout)
            made.append(var)
            offset += size
    except _NotFixed:
        return None
    head = [f"{shared.var} = {src.name('U', shared.struct().unpack_from)}(buf, pos)"] if shared.runs else []
    tail = []
    if batched:  # every model of the fixed parts: made, then filled, each in one C loop
        names = ", ".join(v for v, _, _ in batched)
        classes = src.name("K", tuple(c for _, c, _ in batched))
        head.append(f"({names},) = map(_new, {classes})")
        tail.append(f"any(map(_dict, ({names},), ({', '.join(d for _, _, d in batched)},)))")
    body = "\n    ".join([*head, *src.lines, *tail, f"return [{', '.join(made)}]"])
    exec(f"def decode(buf, pos):\n    {body}\n", src.env)
    return src.env["decode"]  # type: ignore[no-any-return]
