"""Checks that span entries or files: names that must exist, be unique or not overlap.

Each check yields (location, reason); the loader adds file and line.
"""

from __future__ import annotations

from collections.abc import Iterator

from rtde_spec.metamodel.schema import (
    BitfieldSpec,
    CaseSpec,
    EnumSpec,
    FieldsFile,
    FieldSpec,
    LayoutField,
    PrimaryFile,
    Since,
    Spec,
)
from rtde_spec.metamodel.versions import Version

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
    enums = {e.name for e in spec.all_enums}
    bitfields = {b.name for b in spec.all_bitfields}
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
    for i, conflict in enumerate(entry.conflicts):
        cloc: Loc = (*loc, "conflicts", i)
        if conflict.field is not None:
            yield (*cloc, "field"), "field names a message's field; an RTDE field's conflicts are its own"
        if conflict.index is None:
            continue
        if entry.index is None:
            yield (*cloc, "index"), "an index range applies to register families only"
        elif not (entry.index[0] <= conflict.index[0] <= conflict.index[1] <= entry.index[1]):
            yield (*cloc, "index"), f"range {list(conflict.index)} is outside the index {list(entry.index)}"
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
    taken: dict[str, str] = {}
    for part, file in (("enums", spec.enums), ("primary_enums", spec.primary_enums)):
        named: list[tuple[str, list[EnumSpec] | list[BitfieldSpec]]] = [
            ("enums", file.enums),
            ("bitfields", file.bitfields),
        ]
        for kind, entries in named:
            for i, entry in enumerate(entries):
                assert isinstance(entry, (EnumSpec, BitfieldSpec))
                if entry.name in taken:
                    yield (
                        part,
                        (kind, i, "name"),
                        (f"duplicate enum or bitfield {entry.name!r} (also in {taken[entry.name]})"),
                    )
                taken[entry.name] = part
        for i, enum in enumerate(file.enums):
            where: Loc = ("enums", i, "values")
            for loc, reason in _duplicates([v.name for v in enum.values], where, "value name"):
                yield part, loc, reason
            for loc, reason in _duplicates([str(v.value) for v in enum.values], where, "value"):
                yield part, loc, reason
        for i, bitfield in enumerate(file.bitfields):
            where = ("bitfields", i, "bits")
            for loc, reason in _duplicates([b.name for b in bitfield.bits], where, "bit name"):
                yield part, loc, reason
            for loc, reason in _duplicates([str(b.bit) for b in bitfield.bits], where, "bit"):
                yield part, loc, reason


def _lint_packages(spec: Spec) -> Iterator[tuple[str, Loc, str]]:
    pk = spec.packages
    prims = {p.name for p in spec.primitives.primitives}
    codes = [p.code for p in pk.package_types]
    for dup, reason in _duplicates(codes, ("package_types",), "package type"):
        yield "packages", dup, reason
    for i, hfield in enumerate(pk.header):
        if hfield.type not in prims:
            yield "packages", ("header", i, "type"), f"unknown primitive {hfield.type!r}"
    if set(pk.directions) != set(pk.senders):
        yield "packages", ("directions",), f"directions must name each sender once: {', '.join(pk.senders)}"
    names = [m.name for m in pk.messages]
    for dup, reason in _duplicates(names, ("messages",), "message"):
        yield "packages", dup, reason
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
        yield from (
            ("packages", where, reason) for where, reason in _layout(msg.fields, spec, (*loc, "fields"), {})
        )
        for j, fld in enumerate(msg.fields):
            floc: Loc = (*loc, "fields", j)
            if fld.kind not in ("value", "string", "bytes") or fld.count is not None:
                yield "packages", floc, "RTDE packages hold primitives, strings and bytes only"
            elif fld.kind in ("string", "bytes") and fld.length not in ("rest", "uint8"):
                yield "packages", (*floc, "length"), f"{fld.type} needs length: rest or uint8"


def _layout(
    fields: list[LayoutField], spec: Spec, loc: Loc, groups: dict[str, str], documented: bool = True
) -> Found:
    """Kinds, references to earlier fields, that open-ended fields come last, and a doc on each.

    The doc is what reference docs and models show a user; an older layout's fields
    are the current fields again and carry theirs there (`documented=False`).
    """
    prims = {p.name: p for p in spec.primitives.primitives}
    ints = {n for n, p in prims.items() if p.kind == "int"}
    enums = {e.name for e in spec.all_enums}
    seen: list[str] = []
    for i, fld in enumerate(fields):
        floc: Loc = (*loc, i)
        kind = fld.kind
        if fld.name in seen:
            yield (*floc, "name"), f"duplicate field name {fld.name!r}"
        if documented and not (fld.doc or "").strip():
            yield (*floc, "doc"), f"field {fld.name!r} has no doc (say what the document says of it)"
        if fld.enum is not None and fld.enum not in enums:
            yield (*floc, "enum"), f"unknown enum {fld.enum!r}"
        yield from _since(fld.since, spec, (*floc, "since"))
        if kind == "value" and fld.type not in prims:
            yield (*floc, "type"), f"unknown type {fld.type!r}"
        if fld.count is not None and kind != "value":
            yield (*floc, "count"), "count applies to primitive values only"
        if kind in ("string", "bytes"):
            if fld.length != "rest" and fld.length not in ints:
                yield (*floc, "length"), "length must be rest or an integer primitive (a prefix)"
        elif fld.length is not None:
            yield (*floc, "length"), "length applies to string and bytes only"
        if fld.fallback is not None and (fld.length in (None, "rest") or i != len(fields) - 1):
            yield (*floc, "fallback"), "fallback applies to the last field, a prefixed string"
        if fld.format is not None and kind != "string":
            yield (*floc, "format"), "format applies to strings only"
        for ref_key in ("when", "switch"):
            ref = getattr(fld, ref_key)
            if ref is not None and ref not in seen:
                yield (*floc, ref_key), f"{ref_key} refers to {ref!r}, which is not an earlier field"
        if kind == "switch":
            if not fld.cases:
                yield (*floc, "cases"), "a switch needs cases"
            for value, case in (fld.cases or {}).items():
                ctype = case.type if isinstance(case, CaseSpec) else case
                clen = case.length if isinstance(case, CaseSpec) else None
                if ctype == "string" and clen in ints:
                    continue
                if ctype not in prims or clen is not None:
                    yield (*floc, "cases", value), "case type must be a primitive or a prefixed string"
        if kind in ("repeat", "optional"):
            if fld.group is None:
                yield (*floc, "group"), "a group needs a model name (group)"
            elif fld.group in groups:
                yield (*floc, "group"), f"group {fld.group!r} is also defined at {groups[fld.group]}"
            else:
                groups[fld.group] = fld.name
            if kind == "repeat" and fld.when is not None:
                yield (*floc, "when"), "a group is either repeated or conditional"
            yield from _layout(fld.fields or [], spec, (*floc, "fields"), groups, documented)
        elif fld.group is not None or fld.repeat is not None or fld.when is not None:
            yield (*floc, "fields"), "repeat, when and group need fields"
        open_ended = fld.length == "rest" or fld.repeat == "until_end" or kind == "values"
        if open_ended and i != len(fields) - 1:
            culprit = "length" if fld.length == "rest" else "repeat" if fld.repeat == "until_end" else "type"
            yield (*floc, culprit), "only the last field can run to the end"
        seen.append(fld.name)


def _lint_primary(spec: Spec) -> Found:
    pf = spec.primary
    prims = {p.name for p in spec.primitives.primitives}
    enums = {e.name: e for e in spec.all_enums}
    for key in ("header", "subpackage_header"):
        for i, hfield in enumerate(getattr(pf, key)):
            if hfield.type not in prims:
                yield (key, i, "type"), f"unknown primitive {hfield.type!r}"
            if hfield.enum is not None and hfield.enum not in enums:
                yield (key, i, "enum"), f"unknown enum {hfield.enum!r}"
    value_enum_spec = enums.get("GlobalVariableType")
    value_enum = {v.name for v in value_enum_spec.values} if value_enum_spec else set()
    for i, vt in enumerate(pf.value_types):
        if vt.name not in value_enum:
            yield ("value_types", i, "name"), f"{vt.name!r} is not a GlobalVariableType value"
        for attr in ("element", "length"):
            value = getattr(vt, attr)
            if value is not None and value not in prims:
                yield ("value_types", i, attr), f"unknown primitive {value!r}"
    for loc, reason in _duplicates([f.name for f in pf.families], ("families",), "family"):
        yield loc, reason
    for loc, reason in _duplicates([str(f.type) for f in pf.families], ("families",), "message type"):
        yield loc, reason
    yield from _type_numbers(pf, enums)
    groups: dict[str, str] = {}
    for i, fam in enumerate(pf.families):
        floc: Loc = ("families", i)
        if fam.layout == "tagged" and fam.tag not in [p.name for p in fam.prefix]:
            yield (*floc, "tag"), f"tag {fam.tag!r} is not a prefix field"
        if fam.layout != "tagged" and (fam.tag or fam.prefix):
            yield (*floc, "layout"), "tag and prefix belong to tagged families"
        if fam.layout == "opaque" and fam.members:
            yield (*floc, "members"), "an opaque family has no members"
        yield from _layout(fam.prefix, spec, (*floc, "prefix"), groups)
        where: Loc = (*floc, "members")
        yield from _duplicates([m.name for m in fam.members], where, "member")
        yield from _duplicates([str(m.type) for m in fam.members], where, "member type")
        for j, member in enumerate(fam.members):
            mloc: Loc = (*where, j)
            yield from _since(member.since, spec, (*mloc, "since"))
            yield from _layout(member.fields, spec, (*mloc, "fields"), groups)
            current = {f.name for f in member.fields}
            for k, old in enumerate(member.older):
                oloc: Loc = (*mloc, "older", k)
                yield from _layout(old.fields, spec, (*oloc, "fields"), {}, documented=False)
                for m, fld in enumerate(old.fields):
                    if fld.name not in current:
                        yield (*oloc, "fields", m, "name"), f"{fld.name!r} is not a field of {member.name}"


def _type_numbers(pf: PrimaryFile, enums: dict[str, EnumSpec]) -> Iterator[tuple[Loc, str]]:
    """Family and member type numbers are exactly the values of the enums that name them.

    A family's number is a value of the header's type enum; a member's, a value of the
    enum of the field that selects it (the sub-package header's type, or the family's tag);
    and every value of those enums has its family or member, so neither side can drift.
    """

    def tie(
        numbers: dict[int, Loc], enum_name: str | None, what: str, where: Loc
    ) -> Iterator[tuple[Loc, str]]:
        enum = enums.get(enum_name or "")
        if enum is None:
            yield where, f"{what} numbers are tied to no enum"
            return
        values = {v.value: v.name for v in enum.values}
        for number, loc in numbers.items():
            if number not in values:
                yield loc, f"{what} number {number} is not a value of {enum.name}"
        for value, name in values.items():
            if value not in numbers:
                yield where, f"{enum.name}.{name} ({value}) has no {what}"

    families: dict[int, Loc] = {f.type: ("families", i, "type") for i, f in enumerate(pf.families)}
    yield from tie(families, pf.header[1].enum, "message type", ("families",))
    for i, fam in enumerate(pf.families):
        if fam.layout == "opaque":
            continue
        if fam.layout == "subpackages":
            enum_name = pf.subpackage_header[1].enum
        else:
            enum_name = next((p.enum for p in fam.prefix if p.name == fam.tag), None)
        members: dict[int, Loc] = {
            m.type: ("families", i, "members", j, "type") for j, m in enumerate(fam.members)
        }
        yield from tie(members, enum_name, f"{fam.name} member", ("families", i, "members"))


def lint_spec(spec: Spec) -> list[tuple[str, Loc, str]]:
    """Every cross-entry problem of a schema-valid spec, as (part, location, reason)."""
    found = list(_lint_common(spec))
    found += list(_lint_types_enums(spec))
    found += [("fields", loc, reason) for loc, reason in lint_fields_file(spec.fields, spec)]
    found += list(_lint_packages(spec))
    found += [("primary", loc, reason) for loc, reason in _lint_primary(spec)]
    return found
