"""The meta-model of spec/external_control/protocols.yaml: URCL's external-control protocols.

Fixed records of int32 words, described with the same `LayoutField`s as RTDE packages
and primary messages (plus `scale`), so the one layout engine decodes them. Checks
that need the primitives (every type known, every variant within its record, the
selector at the same offset in every variant) are made here, at load time; codegen
then writes the validated file to `_generated/external_control.py`.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from rtde_spec.errors import SpecError, SpecIssue
from rtde_spec.metamodel.schema import EnumSpec, Ident, LayoutField, StrictModel

SPEC_FILE = "external_control/protocols.yaml"
PRIMITIVES_FILE = "common/primitives.yaml"


class Variant(StrictModel):
    """One reading of a record: its whole layout, chosen by the selector's value (`when`)."""

    name: Ident
    when: list[int] | None = None  # None: the default, every value no other variant names
    table: Ident
    doc: str | None = None
    fields: list[LayoutField]


class Detect(StrictModel):
    """How a capture recognises a layout: lines of the program the driver sent (script sender).

    `script_lines` must all be in the program, `without` none of them (a later version keeps
    the lines and adds one); `any_multipliers` names multipliers (`MULT_time`) whose value does
    not matter to this layout's words, so the program may set them to anything.
    """

    source: str
    script_lines: Annotated[list[str], Field(min_length=1)]
    without: list[str] = Field(default_factory=list)
    any_multipliers: list[Annotated[str, Field(pattern=r"^MULT_\w+$")]] = Field(default_factory=list)

    @property
    def lines(self) -> frozenset[str]:
        """The lines as a program is compared with them: whitespace and `#` comments removed."""
        return frozenset(program_line(line) for line in self.script_lines)

    @property
    def absent(self) -> frozenset[str]:
        """The lines the program must not have, compared as `lines` are."""
        return frozenset(program_line(line) for line in self.without)

    def matches(self, program: frozenset[str] | set[str]) -> bool:
        """Whether a program (its lines as `program_line` gives them) names this layout: all of
        its lines, none of its absent ones, and no multiplier it does not name (an unknown
        multiplier: scales the spec does not know) but those whose value it leaves open."""
        open_ = self.any_multipliers
        multipliers = {line for line in program if (name := multiplier(line)) and name not in open_}
        return self.lines <= program and not self.absent & program and multipliers <= self.lines


def program_line(line: str) -> str:
    """A URScript line as `detect` compares it: no comment, no whitespace."""
    return "".join(line.split("#", 1)[0].split())


MULTIPLIER = re.compile(r"(MULT_\w*)=")  # a line setting a multiplier, as program_line gives it


def multiplier(line: str) -> str | None:
    """The multiplier (`MULT_...`) a program line (as `program_line` gives it) sets, if any."""
    found = MULTIPLIER.match(line)
    return found.group(1) if found else None


class OlderRecord(StrictModel):
    """A layout older drivers send (decode on request), with the source that defines it."""

    name: Ident
    source: str
    detect: Detect | None = None
    record_bytes: Annotated[int, Field(ge=1)]
    selector: Ident | None = None
    variants: Annotated[list[Variant], Field(min_length=1)]


class RecordMessage(StrictModel):
    name: Ident
    sender: Literal["driver", "robot"]
    record_bytes: Annotated[int, Field(ge=1)]
    selector: Ident | None = None
    doc: str | None = None
    layout: Ident | None = None  # the newest layout's name (the one `variants` give), beside `older`
    detect: Detect | None = None
    variants: Annotated[list[Variant], Field(min_length=1)]
    older: list[OlderRecord] = Field(default_factory=list)

    def layouts(self) -> list[tuple[str | None, str, Detect | None, int]]:
        """(`layout` argument of the codec: None for the newest, name, detect, record bytes), newest first."""
        newest = (None, self.layout or "newest", self.detect, self.record_bytes)
        return [newest, *((o.name, o.name, o.detect, o.record_bytes) for o in self.older)]


class ExternalProtocol(StrictModel):
    name: Ident
    port: Annotated[int, Field(ge=1, le=65535)]
    doc: str | None = None
    source: str
    messages: list[RecordMessage] = Field(default_factory=list)
    request: str | None = None  # a text request (the script sender's), answered by the program text
    table: Ident | None = None  # where a text exchange's rows go

    @model_validator(mode="after")
    def _one_kind(self) -> ExternalProtocol:
        if bool(self.messages) == (self.request is not None):
            raise ValueError(f"protocol {self.name!r}: give either messages or a text request")
        if self.request is not None and self.table is None:
            raise ValueError(f"protocol {self.name!r}: a text exchange needs a table")
        return self


class ExternalControlFile(StrictModel):
    doc_ref: str
    library: str
    byte_order: Literal["big", "little"]
    enums: list[EnumSpec]
    protocols: list[ExternalProtocol]

    def protocol(self, name: str) -> ExternalProtocol:
        """The protocol of that name; KeyError naming the known ones (a bare StopIteration was raised)."""
        found = next((p for p in self.protocols if p.name == name), None)
        if found is None:
            raise KeyError(
                f"no external-control protocol {name} (known: {', '.join(p.name for p in self.protocols)})"
            )
        return found


def check(spec: ExternalControlFile, prims: dict[str, tuple[int, str]]) -> list[tuple[str, str]]:
    """(path, reason) of every cross-reference problem; `prims`: name -> (size, kind)."""
    issues: list[tuple[str, str]] = []
    enums = {e.name: {v.value for v in e.values} for e in spec.enums}
    names = [p.name for p in spec.protocols]
    ports = [p.port for p in spec.protocols]
    if len(set(names)) != len(names) or len(set(ports)) != len(ports):
        issues.append(("protocols", "a protocol name or port is given twice"))
    for p in spec.protocols:
        for m in p.messages:
            where = f"protocols({p.name}).messages({m.name})"
            issues += _check_record(where, m.record_bytes, m.selector, m.variants, prims, enums)
            for old in m.older:
                issues += _check_record(
                    f"{where}.older({old.name})", old.record_bytes, old.selector, old.variants, prims, enums
                )
            issues += _check_layouts(where, m)
    return issues


def _check_layouts(where: str, message: RecordMessage) -> list[tuple[str, str]]:
    """Layout names unique; detect lines that can tell the layouts apart."""
    issues: list[tuple[str, str]] = []
    layouts = message.layouts()
    names = [name for _, name, _, _ in layouts]
    if len(set(names)) != len(names):
        issues.append((where, "a layout name is given twice (`layout` and the `older` names)"))
    if any(d is not None for _, _, d, _ in layouts) and message.layout is None:
        issues.append((where, "layouts with `detect` need `layout`, the newest's name, to report it by"))
    found = [(name, d) for _, name, d, _ in layouts if d is not None]
    for i, (a, da) in enumerate(found):
        if any(not line for line in da.lines | da.absent):
            issues.append((f"{where}.detect({a})", "an empty script line"))
        if da.lines & da.absent:
            issues.append((f"{where}.detect({a})", "a line both required and `without`: no program has it"))
        if {multiplier(line) for line in da.lines} & set(da.any_multipliers):
            named = "a multiplier both in `script_lines` and `any_multipliers`"
            issues.append((f"{where}.detect({a})", named))
        for b, db in found[i + 1 :]:
            ruled_out = da.absent & db.lines or db.absent & da.lines  # a program with b's lines is not a's
            if not ruled_out and (da.lines <= db.lines or db.lines <= da.lines):
                issues.append((where, f"the detect lines of {a} and {b} cannot tell them apart"))
    return issues


def _check_record(
    where: str,
    size: int,
    selector: str | None,
    variants: list[Variant],
    prims: dict[str, tuple[int, str]],
    enums: dict[str, set[int]],
) -> list[tuple[str, str]]:
    issues: list[tuple[str, str]] = []
    at: set[tuple[int, str]] = set()
    defaults = [v.name for v in variants if v.when is None]
    if len(defaults) > 1 or (selector is None and len(variants) > 1):
        issues.append((where, "one default variant at most, and variants need a selector"))
    for v in variants:
        pos = 0
        for f in v.fields:
            if f.type not in prims or f.fields is not None:
                issues.append((f"{where}.variants({v.name}).{f.name}", f"type {f.type!r} is no primitive"))
                continue
            if f.enum is not None and f.enum not in enums:
                issues.append((f"{where}.variants({v.name}).{f.name}", f"unknown enum {f.enum!r}"))
            if f.scale is not None and prims[f.type][1] not in ("int", "float"):
                issues.append((f"{where}.variants({v.name}).{f.name}", "scale on a value that is no number"))
            if f.name == selector:
                at.add((pos, f.type))
            pos += prims[f.type][0] * (f.count or 1)
        if pos > size:
            issues.append((f"{where}.variants({v.name})", f"{pos} bytes: longer than the {size}-byte record"))
        if selector is not None and selector not in [f.name for f in v.fields]:
            issues.append((f"{where}.variants({v.name})", f"lacks the selector {selector!r}"))
    if len(at) > 1:
        issues.append((where, f"the selector {selector!r} is not at the same offset in every variant"))
    return issues


def load_external(root: Path | str) -> ExternalControlFile:
    """Load, validate and check external_control/protocols.yaml below spec root `root`."""
    from rtde_spec.metamodel.loader import load_file
    from rtde_spec.metamodel.schema import PrimitivesFile

    spec = load_file(root, SPEC_FILE, ExternalControlFile)
    primitives = load_file(root, PRIMITIVES_FILE, PrimitivesFile).primitives
    found = check(spec, {p.name: (p.size, p.kind) for p in primitives})
    if found:
        raise SpecError([SpecIssue(SPEC_FILE, path, reason) for path, reason in found])
    return spec


@cache
def external_spec() -> ExternalControlFile:
    """The built-in external-control protocols, from the generated module."""
    from rtde_spec._generated.external_control import EXTERNAL_CONTROL

    return ExternalControlFile.model_validate(EXTERNAL_CONTROL)
