"""One generated function per Robot State sub-package: few unpacks, then its models.

A Robot State is ~30 frozen models (sub-packages, joints, limits). The general
layout walk costs a dict per group, a regroup pass and a function call per model;
here each sub-package gets straight-line code, built once from the same spec
layout: one unpack per fixed run (fixed groups included), a branch for a
conditional group, a slice for trailing bytes, and every model's own __dict__ filled
key by key, pydantic's bookkeeping slots left to `PrimaryModel.__getattr__` (as
`fast_models.maker` does, minus the call). A part shorter than its
layout returns None and the general walk names what is missing; layouts with
strings, switches or open-ended groups are not compiled.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from rtde_spec._generated import primary_models as gen
from rtde_spec.primary.fast_models import complete
from rtde_spec.wire.layout import Layout

if TYPE_CHECKING:  # annotations only: the meta-model is not built at run time
    from rtde_spec.metamodel.schema import LayoutField

Decoder = Callable[[bytes, int, int], Any]


class Source:
    """Statements of one generated function, and the objects it names."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.indent = ""
        self.env: dict[str, Any] = {"_new": object.__new__}
        self.count = 0

    def name(self, prefix: str, value: Any = None) -> str:
        self.count += 1
        name = f"{prefix}{self.count}"
        if value is not None:
            self.env[name] = value
        return name

    def add(self, *lines: str) -> None:
        self.lines += [self.indent + line for line in lines]

    def model(self, cls: type[BaseModel], entries: list[str]) -> str:
        """Statements making one `cls` from 'key: expression' entries; returns its variable.

        The new instance's own __dict__ is filled key by key: it shares its class's keys
        (a split table, as for instances that set their attributes), which costs less than
        building a dict and setting it as __dict__ (~10 % of a Robot State, by callgrind).
        """
        if set(cls.model_fields) != {e.split(":")[0].strip("'") for e in entries}:
            raise NotFixed
        complete(cls)  # its serializer, before any instance exists (fast_models)
        var, name = self.name("m"), self.name("C", cls)
        self.add(f"{var} = _new({name})", f"d = {var}.__dict__")
        self.add(*(f"d[{key}] = {value}" for key, value in (e.split(": ", 1) for e in entries)))
        return var


class NotFixed(Exception):
    """The layout has a part the generated code does not cover: the general path decodes it."""


def _fields(src: Source, fields: list[LayoutField], t: str | list[str], index: int) -> tuple[list[str], int]:
    """'name: expression' entries for fixed fields read from tuple `t` at `index`
    (or from the variables `t` names, one per value)."""
    entries = []
    for fld in fields:
        if fld.scale is not None:  # the wire holds value x scale: the general walk divides
            raise NotFixed
        if fld.kind == "value":
            count = fld.count or 1
            if isinstance(t, list):
                expr = t[index] if fld.count is None else f"({', '.join(t[index : index + count])},)"
            else:
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
            raise NotFixed
    return entries, index


def unpack_run(src: Source, layout: Layout, fields: list[LayoutField]) -> list[str]:
    """Statements reading one fixed run at p (None when the part is too short); its entries."""
    step = Layout(fields, layout.prims, order=layout.order)._single
    if step is None:
        raise NotFixed
    unpack, size = src.name("U", step.struct.unpack_from), step.struct.size
    names = [src.name("v") for _ in step.struct.unpack(bytes(size))]  # a local per value
    read = f"({', '.join(names)},) = {unpack}(buf, p)"
    src.add(f"if end - p < {size}:", "    return None", read, f"p += {size}")
    entries, _ = _fields(src, fields, names, 0)
    return entries


def entries_of(
    src: Source, layout: Layout, fields: Sequence[Any], other: Callable[[Any, list[str]], str]
) -> list[str]:
    """'name: expression' entries of `fields` in order: each run of fixed fields read by one
    unpack, any other field by `other(field, entries so far)`, which returns its expression
    (or raises NotFixed)."""
    entries: list[str] = []
    run: list[Any] = []
    for fld in fields:
        if fld.kind == "value" or (fld.kind == "repeat" and isinstance(fld.repeat, int)):
            run.append(fld)
            continue
        if run:
            entries += unpack_run(src, layout, run)
            run = []
        entries.append(f"{fld.name!r}: {other(fld, entries)}")
    if run:
        entries += unpack_run(src, layout, run)
    return entries


def _body(src: Source, layout: Layout) -> list[str]:
    """Entries of every field: fixed runs, conditional fixed groups, a trailing rest of bytes/text."""

    def other(fld: LayoutField, entries: list[str]) -> str:
        if fld.kind == "optional" and fld.group is not None:
            flag = next(e.split(": ", 1)[1] for e in entries if e.startswith(repr(fld.when) + ":"))
            var = src.name("o")
            src.add(f"if {flag}:")
            src.indent += "    "
            inner = unpack_run(src, layout, fld.fields or [])
            src.add(f"{var} = {src.model(gen.GROUPS[fld.group], inner)}")
            src.indent = src.indent[:-4]
            src.add("else:", f"    {var} = None")
            return var
        if fld.kind == "bytes" and fld.length == "rest" and fld is layout.fields[-1]:
            src.add("rest = buf[p:end]", "p = end")
            return "rest"
        raise NotFixed

    return entries_of(src, layout, layout.fields, other)


def _emit_part(src: Source, cls: type[BaseModel], layout: Layout) -> str:
    """Statements decoding one part between `p` and `end`; returns the variable of its model."""
    entries = _body(src, layout)
    return src.model(cls, [*entries, "'missing': ()", "'extra': buf[p:end]"])


def compile_part(cls: type[BaseModel], layout: Layout) -> Decoder | None:
    """decode(buf, start, end) -> the part's model, or None when the part is shorter than its layout.

    None from compile_part itself: the layout has strings, switches or open-ended groups,
    which the general path decodes. Bytes after the layout are the part's `extra`.
    """
    src = Source()
    src.add("p = start")
    try:
        part = _emit_part(src, cls, layout)
    except NotFixed:
        return None
    body = "\n    ".join([*src.lines, f"return {part}"])
    exec(f"def decode(buf, start, end):\n    {body}\n", src.env)
    return src.env["decode"]  # type: ignore[no-any-return]


ShapeDecoder = Callable[[bytes, int, list[Any]], "list[Any] | None"]


class CompiledShape:
    """The generated decoder of one shape, and a blank cache of its sub-packages' last models.

    `decode(buf, pos, cache)`: the models of the sub-packages at `pos`, or None when the
    bytes are not of this shape (a header differs) or a part is shorter than its layout
    (the general walk then decodes them). A sub-package whose bytes equal the ones `cache`
    holds for its slot is the model decoded from them before (the same object: the models
    are frozen and hold only immutable values, and equal bytes decode to equal models);
    any other is decoded and put in its slot. A slot holds one (bytes, model) tuple,
    replaced whole, so threads sharing a cache never pair one sub-package's bytes with
    another's model; a blank slot holds no bytes a sub-package can equal.
    """

    __slots__ = ("blank", "decode", "shared")

    def __init__(self, decode: ShapeDecoder, blank: tuple[tuple[Any, Any], ...]) -> None:
        self.decode = decode
        self.blank = blank
        self.shared = self.cache()  # for callers that keep none of their own (decode_message)

    def cache(self) -> list[Any]:
        """A new cache: one slot per sub-package of the shape."""
        return list(self.blank)


def _fixed_part(
    src: Source, cls: type[BaseModel], layout: Layout, part: str, head: struct.Struct, whole: int, kind: int
) -> str | None:
    """A part of fixed fields (and perhaps trailing rest-of-part bytes) in the bytes `part`
    (its header included, `whole` of them): one unpack of its header and fields, the header
    checked against (whole, kind), its models made by one C loop and filled by another;
    None when it has other fields."""
    fields, rest = list(layout.fields), None
    if fields and fields[-1].kind == "bytes" and fields[-1].length == "rest":
        rest = fields.pop()
    if any(f.kind != "value" and not (f.kind == "repeat" and isinstance(f.repeat, int)) for f in fields):
        return None
    step = Layout(fields, layout.prims, order=layout.order)._single if fields else None
    if fields and step is None:
        raise NotFixed
    fmt = struct.Struct(head.format + (step.struct.format[1:] if step is not None else ""))
    if whole < fmt.size:  # shorter than its layout: the general walk names what is missing
        raise NotFixed
    names = [src.name("v") for _ in fmt.unpack(bytes(fmt.size))]
    src.add(
        f"({', '.join(names)},) = {src.name('U', fmt.unpack_from)}({part})",
        f"if {names[0]} != {whole} or {names[1]} != {kind}:",
        "    return None",
    )
    entries, _ = _fields(src, fields, names[2:], 0) if fields else ([], 0)
    tail = f"{part}[{fmt.size}:]" if fmt.size < whole else "b''"
    if rest is not None:
        entries.append(f"{rest.name!r}: {tail}")
        tail = "b''"
    return src.model(cls, [*entries, "'missing': ()", f"'extra': {tail}"])


def compile_shape(
    parts: list[tuple[type[BaseModel], Layout, int]], head: struct.Struct
) -> CompiledShape | None:
    """A decoder of a run of sub-packages of exactly these (class, layout, size including
    header; `head` the sub-package header: size, type), in one function: no loop, no call
    per part. One unpack cuts the message into its sub-packages' bytes; each is compared
    with the cache's, and only a part that changed is unpacked (one unpack, its header
    checked) and made.

    A controller sends the same sub-packages every time, and at 10 Hz many of them
    (kinematics, configuration, safety, tool communication) keep their bytes: a Robot State
    of a shape seen before is decoded by straight-line code that decodes only what changed.
    None from compile_shape: a part is shorter than its layout, or has a layout the
    generated code does not cover.
    """
    src = Source()
    made, blank, pieces, split = [], [], [], []
    try:
        for slot, (cls, layout, size) in enumerate(parts):
            part, kind = src.name("p"), cls.TYPE  # type: ignore[attr-defined]
            split.append(part)
            pieces.append(f"{size}s")
            mark = len(src.lines)
            src.indent = "    "
            var = _fixed_part(src, cls, layout, part, head, size, kind)
            if var is None:  # a conditional group: this part reads as a part alone does
                src.add(
                    f"if {src.name('S', head.unpack_from)}({part}) != ({size}, {kind}):",
                    "    return None",
                    f"buf, p, end = {part}, {head.size}, {size}",
                )
                var = _emit_part(src, cls, layout)
            src.add(f"c[{slot}] = ({part}, {var})")
            src.lines[mark:mark] = [f"e = c[{slot}]", f"if {part} == e[0]:", f"    {var} = e[1]", "else:"]
            made.append(var)
            blank.append((None, None))
    except NotFixed:
        return None
    cut = src.name("B", struct.Struct(head.format[0] + "".join(pieces)).unpack_from)
    lines = [f"({', '.join(split)},) = {cut}(buf, pos)", *src.lines, f"return [{', '.join(made)}]"]
    body = "\n    ".join(lines)
    exec(f"def decode(buf, pos, c):\n    {body}\n", src.env)
    return CompiledShape(src.env["decode"], tuple(blank))
