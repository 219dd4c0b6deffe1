"""The meta-model of spec/realtime/interface.yaml: the real-time interface's message (port 30003).

Its fields are the primary interface's layout fields (one layout language) with two
keys more: `rtde`, the RTDE output carrying the same quantity, and `integer`, a whole
number carried in a double. The file is read without YAML aliases; unknown keys, a
field given twice, a group or string where only fixed values fit, or `lengths` that the
fields do not add up to, or an `rtde` name that is no RTDE output are errors naming the
file and the entry. codegen writes the
validated file to `_generated/realtime.py`, so the installed package needs no YAML.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from rtde_spec.errors import SpecError, SpecIssue
from rtde_spec.metamodel.catalogue import Catalogue, LineInfo
from rtde_spec.metamodel.schema import LayoutField, Source, StrictModel, VersionStr
from rtde_spec.metamodel.versions import Version

SPEC_FILE = "realtime/interface.yaml"
#: struct format character and size of the primitives a real-time message may hold
PRIMITIVES = {"double": ("d", 8), "int32": ("i", 4), "uint64": ("Q", 8)}


class RealtimeField(LayoutField):
    """A fixed field of the real-time message: a primitive, `count` of them."""

    rtde: str | None = None
    integer: bool = False

    @model_validator(mode="after")
    def _fixed(self) -> RealtimeField:
        if self.kind != "value" or self.type not in PRIMITIVES:
            raise ValueError(
                f"field {self.name!r}: only {', '.join(PRIMITIVES)} values (with count) fit here"
            )
        return self


class MessageLength(StrictModel):
    version: VersionStr
    length: Annotated[int, Field(ge=8)]
    sources: Annotated[list[Source], Field(min_length=1)]


class RealtimeFile(StrictModel):
    doc_ref: str
    byte_order: Literal["big"]
    ports: dict[str, Annotated[int, Field(ge=1, le=65535)]]
    max_message_bytes: Annotated[int, Field(ge=64)]
    header: list[RealtimeField]
    fields: list[RealtimeField]
    lengths: list[MessageLength]

    @model_validator(mode="after")
    def _consistent(self) -> RealtimeFile:
        seen: set[str] = set()
        for f in [*self.header, *self.fields]:
            if f.name in seen:
                raise ValueError(f"field {f.name!r} is given twice")
            seen.add(f.name)
        if len(self.header) != 1 or self.header[0].type != "int32":
            raise ValueError("the header is one int32: the message size")
        return self


@dataclass(frozen=True)
class LayoutPlan:
    """The message of one product line from one version on: its fields and compiled format."""

    line: str
    first: str  # the first version of the line that sends exactly these fields
    fields: tuple[RealtimeField, ...]  # the header's size field not included

    @property
    def size(self) -> int:
        """Bytes of the whole message, header included."""
        return 4 + sum(PRIMITIVES[f.type][1] * (f.count or 1) for f in self.fields)

    @property
    def format(self) -> str:
        """struct format of the whole message (big-endian), header included."""
        return ">i" + "".join(f"{f.count or ''}{PRIMITIVES[f.type][0]}" for f in self.fields)


def _sent(since: dict[str, str] | None, line: LineInfo, version: Version) -> bool:
    """Whether a field is sent by `version` of `line`: no `since` is every version of the line."""
    if since is None:
        return True
    if line.id in since:
        return version >= Version.parse(since[line.id])
    return line.inherits is not None and line.inherits in since


def layouts(table: RealtimeFile, catalogue: Catalogue) -> list[LayoutPlan]:
    """Per product line, one plan per version a field appears at, oldest first."""
    plans = []
    for line in catalogue.lines.values():
        starts = {Version(min(line.majors))}
        for f in table.fields:
            if f.since and line.id in f.since:
                starts.add(Version.parse(f.since[line.id]))
        for start in sorted(starts):
            fields = tuple(f for f in table.fields if _sent(f.since, line, start))
            plans.append(LayoutPlan(line.id, str(start), fields))
    return plans


def check_lengths(table: RealtimeFile, catalogue: Catalogue) -> list[SpecIssue]:
    """The documented message sizes the fields do not add up to (none when the spec is right)."""
    issues = []
    for i, entry in enumerate(table.lengths):
        version = Version.parse(entry.version)
        line = catalogue.line_of(version).id
        plans = [p for p in layouts(table, catalogue) if p.line == line]
        plan = [p for p in plans if Version.parse(p.first) <= version][-1]
        if plan.size != entry.length:
            reason = (
                f"version {entry.version}: the fields add up to {plan.size} bytes, "
                f"the sources give {entry.length}"
            )
            issues.append(SpecIssue(SPEC_FILE, f"lengths.{i}", reason))
    return issues


def load_realtime(root: Path | str, catalogue: Catalogue | None = None) -> RealtimeFile:
    """Load and validate realtime/interface.yaml below spec root `root`; SpecError says what is wrong.

    With a catalogue (its product lines), the documented message sizes are checked too.
    """
    from rtde_spec.metamodel.loader import load_file

    table = load_file(root, SPEC_FILE, RealtimeFile)
    if catalogue is not None:
        names = set(catalogue.names("output"))
        issues = check_lengths(table, catalogue) + [
            SpecIssue(SPEC_FILE, f"fields.{i}.rtde", f"{f.rtde!r} is no RTDE output")
            for i, f in enumerate(table.fields)
            if f.rtde is not None and f.rtde not in names
        ]
        if issues:
            raise SpecError(issues)
    return table


@cache
def realtime_spec() -> RealtimeFile:
    """The built-in real-time interface, validated from the generated module."""
    from rtde_spec._generated.realtime import REALTIME

    return RealtimeFile.model_validate(REALTIME)
