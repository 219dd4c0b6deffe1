"""Checks that span entries or files: names that must exist, be unique or not overlap.

Each check yields (location, reason); the loader adds file and line.
"""

from __future__ import annotations

from collections.abc import Iterator

from .spec_schema import FieldsFile, FieldSpec, Since, Spec
from .versions import Version

Loc = tuple[str | int, ...]
Found = Iterator[tuple[Loc, str]]


def _duplicates(names: list[str], where: Loc, what: str) -> Found:
    seen: set[str] = set()
    for i, name in enumerate(names):
        if name in seen:
            yield (*where, i), f"duplicate {what} {name!r}"
        seen.add(name)


def _since(since: Since | None, spec: Spec, loc: Loc) -> Found:
    lines = {line.id: line for line in spec.product_lines.product_lines}
    for line_id, text in (since or {}).items():
        line = lines.get(line_id)
        if line is None:
            yield (*loc, line_id), f"unknown product line {line_id!r} (known: {', '.join(lines)})"
            continue
        version = Version.parse(text)
        if version.major not in line.majors:
            yield (
                (*loc, line_id),
                (f"version {text} is not on line {line_id} (majors {line.majors})"),
            )


def _field(entry: FieldSpec, spec: Spec, loc: Loc) -> Found:
    types = {t.name: t for t in spec.types.types}
    enums = {e.name for e in spec.enums.enums}
    bitfields = {b.name for b in spec.enums.bitfields}
    primitives = {p.name: p for p in spec.primitives.primitives}
    wire = types.get(entry.type)
    if wire is None:
        yield (*loc, "type"), f"unknown type {entry.type!r} (known: {', '.join(types)})"
    prim = primitives.get(wire.element or "") if wire else None
    integer = prim is not None and prim.kind == "int"
    if entry.enum is not None:
        if entry.enum not in enums:
            yield (*loc, "enum"), f"unknown enum {entry.enum!r}"
        elif prim and not integer:
            yield (*loc, "enum"), f"enum {entry.enum!r} on non-integer type {entry.type}"
    if entry.bits is not None:
        if entry.bits not in bitfields:
            yield (*loc, "bits"), f"unknown bitfield {entry.bits!r}"
        elif prim and not integer:
            yield (*loc, "bits"), f"bitfield {entry.bits!r} on non-integer type {entry.type}"
    yield from _since(entry.since, spec, (*loc, "since"))
    has_placeholder = "{X}" in entry.name
    if entry.index is None:
        if has_placeholder:
            yield (*loc, "name"), "name has {X} but no index range is given"
        if entry.ranges:
            yield (*loc, "ranges"), "ranges need an index range on the field"
        return
    if not has_placeholder:
        yield (*loc, "name"), "an indexed field needs {X} in its name"
    low, high = entry.index
    if low > high:
        yield (*loc, "index"), f"index range [{low}, {high}] is empty"
    spans: list[tuple[int, int, int]] = []
    for i, rng in enumerate(entry.ranges or []):
        rloc = (*loc, "ranges", i)
        a, b = rng.index
        if a > b:
            yield (*rloc, "index"), f"range [{a}, {b}] is empty"
        if a < low or b > high:
            yield (
                (*rloc, "index"),
                f"range [{a}, {b}] lies outside the field's index [{low}, {high}]",
            )
        for c, d, j in spans:
            if a <= d and c <= b:
                yield (*rloc, "index"), f"range [{a}, {b}] overlaps range {j} [{c}, {d}]"
        spans.append((a, b, i))
        yield from _since(rng.since, spec, (*rloc, "since"))


def lint_fields_file(fields: FieldsFile, spec: Spec, against: FieldsFile | None = None) -> Found:
    """Check a fields file; with `against`, names already there count as duplicates."""
    for direction in ("inputs", "outputs"):
        entries: list[FieldSpec] = getattr(fields, direction)
        taken: dict[str, str] = {}
        if against is not None:
            for entry in getattr(against, direction):
                for name, _ in entry.concrete():
                    taken[name] = f"the built-in {direction}"
        for i, entry in enumerate(entries):
            loc: Loc = (direction, i)
            yield from _field(entry, spec, loc)
            for name, _ in entry.concrete():
                if name in taken:
                    yield (*loc, "name"), f"duplicate name {name!r} in {direction} ({taken[name]})"
                    break
            for name, _ in entry.concrete():
                taken.setdefault(name, f"entry {i}")


def _lint_common(spec: Spec) -> Iterator[tuple[str, Loc, str]]:
    prims = spec.primitives.primitives
    for loc, reason in _duplicates([p.name for p in prims], ("primitives",), "primitive"):
        yield "primitives", loc, reason
    for i, prim in enumerate(prims):
        if prim.kind == "int" and prim.signed is None:
            yield "primitives", ("primitives", i, "signed"), "integer primitives need signed"
    lines = spec.product_lines.product_lines
    ids = [line.id for line in lines]
    for loc, reason in _duplicates(ids, ("product_lines",), "product line"):
        yield "product_lines", loc, reason
    majors: dict[int, str] = {}
    for i, line in enumerate(lines):
        loc = ("product_lines", i)
        if line.inherits is not None and line.inherits not in ids:
            yield "product_lines", (*loc, "inherits"), f"unknown product line {line.inherits!r}"
        if Version.parse(line.first_version).major not in line.majors:
            yield "product_lines", (*loc, "first_version"), "first_version is not on this line"
        for major in line.majors:
            if major in majors:
                yield "product_lines", (*loc, "majors"), f"major {major} is also {majors[major]}"
            majors[major] = line.id


def _lint_types_enums(spec: Spec) -> Iterator[tuple[str, Loc, str]]:
    prims = {p.name for p in spec.primitives.primitives}
    types = spec.types.types
    for loc, reason in _duplicates([t.name for t in types], ("types",), "type"):
        yield "types", loc, reason
    for i, wire in enumerate(types):
        if wire.variable and wire.element is not None:
            yield "types", ("types", i, "element"), "a variable type has no element"
        elif not wire.variable and wire.element not in prims:
            yield "types", ("types", i, "element"), f"unknown primitive {wire.element!r}"
    enums, bitfields = spec.enums.enums, spec.enums.bitfields
    names = [e.name for e in enums] + [b.name for b in bitfields]
    for (_, i), reason in _duplicates(names, ("",), "enum or bitfield"):
        assert isinstance(i, int)
        loc = ("enums", i) if i < len(enums) else ("bitfields", i - len(enums))
        yield "enums", loc, reason
    for i, enum in enumerate(enums):
        where: Loc = ("enums", i, "values")
        for loc, reason in _duplicates([v.name for v in enum.values], where, "value name"):
            yield "enums", loc, reason
        for loc, reason in _duplicates([str(v.value) for v in enum.values], where, "value"):
            yield "enums", loc, reason
    for i, bitfield in enumerate(bitfields):
        where = ("bitfields", i, "bits")
        for loc, reason in _duplicates([b.name for b in bitfield.bits], where, "bit name"):
            yield "enums", loc, reason
        for loc, reason in _duplicates([str(b.bit) for b in bitfield.bits], where, "bit"):
            yield "enums", loc, reason


def _lint_packages(spec: Spec) -> Iterator[tuple[str, Loc, str]]:
    pk = spec.packages
    prims = {p.name for p in spec.primitives.primitives}
    enums = {e.name for e in spec.enums.enums}
    codes = [p.code for p in pk.package_types]
    for loc, reason in _duplicates(codes, ("package_types",), "package type"):
        yield "packages", loc, reason
    for i, hfield in enumerate(pk.header):
        if hfield.type not in prims:
            yield "packages", ("header", i, "type"), f"unknown primitive {hfield.type!r}"
    names = [m.name for m in pk.messages]
    for loc, reason in _duplicates(names, ("messages",), "message"):
        yield "packages", loc, reason
    claimed: dict[tuple[str, str, int], str] = {}
    for i, msg in enumerate(pk.messages):
        loc: Loc = ("messages", i)
        if msg.type not in codes:
            yield "packages", (*loc, "type"), f"unknown package type {msg.type!r}"
        for sender in msg.senders:
            if sender not in pk.senders:
                yield "packages", (*loc, "sender"), f"unknown sender {sender!r}"
            for proto in msg.protocols:
                key = (msg.type, sender, proto)
                if key in claimed:
                    yield (
                        "packages",
                        (*loc, "protocols"),
                        (f"{msg.type!r} from {sender} in protocol {proto} is also {claimed[key]}"),
                    )
                claimed[key] = msg.name
        for j, fld in enumerate(msg.fields):
            floc: Loc = (*loc, "fields", j)
            if fld.type in ("string", "bytes"):
                if fld.length is None:
                    yield "packages", (*floc, "length"), f"{fld.type} needs length: rest or uint8"
                if fld.length == "rest" and j != len(msg.fields) - 1:
                    yield "packages", (*floc, "length"), "only the last field can run to the end"
            elif fld.type not in prims:
                yield "packages", (*floc, "type"), f"unknown type {fld.type!r}"
            elif fld.length is not None:
                yield "packages", (*floc, "length"), "length applies to string and bytes only"
            if fld.format is not None and fld.type != "string":
                yield "packages", (*floc, "format"), "format applies to strings only"
            if fld.enum is not None and fld.enum not in enums:
                yield "packages", (*floc, "enum"), f"unknown enum {fld.enum!r}"


def lint_spec(spec: Spec) -> list[tuple[str, Loc, str]]:
    """Every cross-entry problem of a schema-valid spec, as (part, location, reason)."""
    found = list(_lint_common(spec))
    found += list(_lint_types_enums(spec))
    found += [("fields", loc, reason) for loc, reason in lint_fields_file(spec.fields, spec)]
    found += list(_lint_packages(spec))
    return found
