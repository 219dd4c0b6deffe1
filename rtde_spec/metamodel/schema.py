"""The meta-model: pydantic classes one YAML file of spec/ must validate against.

Unknown keys are errors (extra="forbid"), so a typo in the spec cannot silently
drop a fact. Checks that need more than one file live in spec_lint.
"""

from __future__ import annotations

import re
from typing import Annotated, Literal

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field, model_validator

from rtde_spec.metamodel.versions import Version
from rtde_spec.wire.kinds import field_kind, int_bounds

_IDENT = r"^[A-Za-z_][A-Za-z0-9_]*$"


def _check_version(value: object) -> object:
    if not isinstance(value, str):
        raise ValueError(
            f"bad version string {value!r}: write MAJOR.MINOR.BUGFIX, e.g. 3.3.0 (YAML reads 3.3 as a number)"
        )
    Version.parse(value)
    return value


VersionStr = Annotated[str, BeforeValidator(_check_version)]
Ident = Annotated[str, Field(pattern=_IDENT)]


def _check_field_name(value: str) -> str:
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*(\{X\})?[A-Za-z0-9_]*", value):
        raise ValueError(f"bad field name {value!r}: letters, digits, _ and at most one {{X}}")
    return value


FieldName = Annotated[str, AfterValidator(_check_field_name)]


class StrictModel(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


# --- spec/common -----------------------------------------------------------


class Primitive(StrictModel):
    name: Ident
    size: Annotated[int, Field(ge=1, le=8)]
    struct: Annotated[str, Field(pattern=r"^[?bBhHiIqQfd]$")]
    kind: Literal["int", "float", "bool"]
    signed: bool | None = None
    doc: str | None = None

    @property
    def bounds(self) -> tuple[int, int] | None:
        """Inclusive integer range, derived from size and signedness."""
        return int_bounds(self.kind, self.size, self.signed)


class PrimitivesFile(StrictModel):
    primitives: list[Primitive]


class ProductLine(StrictModel):
    id: Annotated[str, Field(pattern=r"^[a-z0-9-]+$")]
    name: str
    majors: list[int]
    first_version: VersionStr
    inherits: str | None = None
    rtde_max_frequency: Annotated[int, Field(ge=1)]
    #: the documented limit of a setup's comma-joined names; None: only the package size bounds it
    rtde_setup_names_max_bytes: Annotated[int, Field(ge=1)] | None = None
    doc: str | None = None


class ProductLinesFile(StrictModel):
    product_lines: list[ProductLine]


# --- spec/rtde/types.yaml --------------------------------------------------


class WireType(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Z0-9_]*$")]
    element: str | None = None
    count: Annotated[int, Field(ge=1)] = 1
    variable: bool = False
    doc: str | None = None


class SetupAnswer(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Z0-9_]*$")]
    doc: str | None = None


class TypesFile(StrictModel):
    doc_ref: str | None = None
    types: list[WireType]
    setup_answers: list[SetupAnswer] = []


# --- spec/rtde/fields.yaml -------------------------------------------------

Since = dict[str, VersionStr]
IndexRange = tuple[Annotated[int, Field(ge=0)], Annotated[int, Field(ge=0)]]
#: a document id: cb3-guide, e-series-guide, third-party, user, or a document an import named
Source = Annotated[str, Field(pattern=r"^[a-z0-9][a-z0-9.-]*$")]
#: what an import can find different between a document and the spec
DiffWhat = Literal[
    "added", "removed", "type", "direction", "availability", "range", "description", "name", "length"
]


class Conflict(StrictModel):
    """A difference a document shows against the spec, decided on purpose.

    `spec import` suppresses exactly this difference (what, the document's value as
    the importer prints it, and the index range for register families) and shows it
    with --show-known; any other difference of the same field is still reported.
    """

    what: DiffWhat
    field: str | None = None  # on a message: the document's name of the field it adds
    document: str | None = None
    index: IndexRange | None = None
    sources: Annotated[list[Source], Field(min_length=1)]
    decision: Annotated[str, Field(min_length=1)]


class RangeSpec(StrictModel):
    index: IndexRange
    since: Since | None = None
    reserved: str | None = None


class FieldSpec(StrictModel):
    name: FieldName
    type: str
    doc: str | None = None
    unit: str | None = None
    enum: str | None = None
    bits: str | None = None
    since: Since | None = None
    index: IndexRange | None = None
    ranges: list[RangeSpec] | None = None
    reserved: str | None = None
    deprecated: str | None = None
    doc_ref: str | None = None
    sources: list[Source] = []
    conflicts: list[Conflict] = []

    @property
    def is_family(self) -> bool:
        return self.index is not None

    def concrete(self) -> list[tuple[str, int | None]]:
        """(name, index) of every concrete field this entry declares."""
        if self.index is None:
            return [(self.name, None)]
        low, high = self.index
        return [(self.name.replace("{X}", str(i)), i) for i in range(low, high + 1)]

    def range_for(self, index: int | None) -> RangeSpec | None:
        """The `ranges` entry that covers a family index, if any."""
        for entry in self.ranges or []:
            if index is not None and entry.index[0] <= index <= entry.index[1]:
                return entry
        return None


class FieldsFile(StrictModel):
    doc_ref: str | None = None
    inputs: list[FieldSpec] = []
    outputs: list[FieldSpec] = []


# --- spec/rtde/enums.yaml --------------------------------------------------


class EnumValue(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Za-z0-9_]*$")]
    value: int
    doc: str | None = None


class EnumSpec(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Za-z0-9]*$")]
    doc: str | None = None
    doc_ref: str | None = None
    values: list[EnumValue]


class BitSpec(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Z0-9_]*$")]
    bit: Annotated[int, Field(ge=0, le=63)]
    doc: str | None = None


class BitfieldSpec(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Za-z0-9]*$")]
    doc: str | None = None
    doc_ref: str | None = None
    bits: list[BitSpec]


class EnumsFile(StrictModel):
    enums: list[EnumSpec] = []
    bitfields: list[BitfieldSpec] = []


# --- spec/rtde/packages.yaml -----------------------------------------------


class CaseSpec(StrictModel):
    type: str
    length: str | None = None


class LayoutField(StrictModel):
    """One field of a primary-interface layout: a value, a string, or a group."""

    name: Ident
    type: str = ""  # a primitive, "string", "bytes" or "variable_values"; empty for groups and switches
    count: Annotated[int, Field(ge=1)] | None = None
    length: str | None = None
    fallback: Literal["rest"] | None = None  # a prefix that does not fit exactly: the string is the rest
    peers: str | None = None  # how other implementations read it, with sources, and the decision taken
    format: Literal["lines", "csv"] | None = None
    repeat: Annotated[int, Field(ge=1)] | Literal["until_end"] | None = None
    when: str | None = None
    switch: str | None = None
    cases: dict[int, str | CaseSpec] | None = None
    group: Annotated[str, Field(pattern=r"^[A-Z][A-Za-z0-9]*$")] | None = None
    fields: list[LayoutField] | None = None
    enum: str | None = None
    unit: str | None = None
    scale: Annotated[float, Field(gt=0)] | None = None  # the wire holds value x scale (URCL's MULT_*)
    doc: str | None = None
    since: Since | None = None  # the first version per product line that sends this field
    source: str | None = None  # the public source of a field the interface document does not describe
    conflicts: list[Conflict] = []  # differences a document shows, decided on purpose

    @model_validator(mode="after")
    def _scale_on_values(self) -> LayoutField:
        if self.scale is not None and self.kind != "value":
            raise ValueError(f"scale is for numbers; {self.name!r} is a {self.kind}")
        return self

    @property
    def kind(self) -> str:
        """value | string | bytes | values | repeat | optional | switch."""
        return field_kind(self.type, self.fields is not None, self.when, self.switch)


PackageField = LayoutField  # one field model for RTDE packages and primary messages


class PackageTypeSpec(StrictModel):
    code: Annotated[str, Field(min_length=1, max_length=1)]
    name: str


class MessageSpec(StrictModel):
    name: Ident
    type: Annotated[str, Field(min_length=1, max_length=1)]
    sender: str | list[str]
    protocols: list[int]
    doc: str | None = None
    fields: list[LayoutField]

    @property
    def senders(self) -> tuple[str, ...]:
        return (self.sender,) if isinstance(self.sender, str) else tuple(self.sender)


class Limits(StrictModel):
    input_recipes_max: int
    invalid_recipe_id: int
    package_max_bytes: int


class Answers(StrictModel):
    not_found: Annotated[str, Field(pattern=r"^[A-Z_]+$")]
    in_use: Annotated[str, Field(pattern=r"^[A-Z_]+$")]


class RecipeIdRule(StrictModel):
    """Whether the data packages of some protocols and senders carry the recipe id byte, and who says so."""

    protocols: Annotated[list[int], Field(min_length=1)]
    senders: Annotated[list[str], Field(min_length=1)]
    recipe_id: Literal["always", "optional"]
    implied: Annotated[int, Field(ge=0, le=255)] | None = None  # the recipe of a package without the byte
    sent: Literal["with", "without"] | None = None  # the form the sender sends (the emulator writes it)
    doc: str | None = None
    sources: Annotated[list[str], Field(min_length=1)]

    @model_validator(mode="after")
    def _implied_when_optional(self) -> RecipeIdRule:
        optional = self.recipe_id == "optional"
        if optional != (self.implied is not None) or optional != (self.sent is not None):
            raise ValueError("`implied` and `sent` are given exactly when recipe_id is optional")
        return self


class PackagesFile(StrictModel):
    port: int
    doc_ref: str | None = None
    byte_order: Literal["big", "little"]
    answers: Answers
    directions: dict[str, Literal["input", "output"]]
    limits: Limits
    data_recipe_id: list[RecipeIdRule] = []
    header: list[LayoutField]
    senders: dict[str, str]
    package_types: list[PackageTypeSpec]
    messages: list[MessageSpec]


# --- spec/primary/interface.yaml -------------------------------------------


class OlderLayout(StrictModel):
    """The layout controllers before `before` send (decode only), with the public source for it."""

    before: VersionStr
    source: str
    fields: list[LayoutField]


class MemberSpec(StrictModel):
    name: Ident
    type: int
    doc: str | None = None
    doc_ref: str | None = None
    source: str | None = None  # public sources of what the member's layout says beyond the document
    since: Since | None = None
    fields: list[LayoutField]
    older: list[OlderLayout] = []
    conflicts: list[Conflict] = []


class FamilySpec(StrictModel):
    name: Ident
    type: int
    layout: Literal["subpackages", "tagged", "opaque"]
    tag: str | None = None
    doc: str | None = None
    prefix: list[LayoutField] = []
    members: list[MemberSpec] = []
    conflicts: list[Conflict] = []  # a document's member the spec leaves out on purpose (field: its title)


class ValueTypeSpec(StrictModel):
    name: Annotated[str, Field(pattern=r"^[A-Z][A-Z0-9_]*$")]
    kind: Literal["none", "string", "scalar", "list", "matrix"]
    element: str | None = None
    count: Annotated[int, Field(ge=1)] = 1
    length: str | None = None


class PrimaryFile(StrictModel):
    byte_order: Literal["big", "little"]
    doc_ref: str | None = None
    ports: dict[str, int]
    max_message_bytes: Annotated[int, Field(ge=16)]
    header: list[LayoutField]
    subpackage_header: list[LayoutField]
    value_separator: Annotated[int, Field(ge=0, le=255)]
    value_types: list[ValueTypeSpec]
    families: list[FamilySpec]


# --- the whole spec --------------------------------------------------------


class Spec(StrictModel):
    """Every file of spec/, validated and linted; the input of every emitter."""

    primitives: PrimitivesFile
    product_lines: ProductLinesFile
    types: TypesFile
    fields: FieldsFile
    enums: EnumsFile
    packages: PackagesFile
    primary_enums: EnumsFile
    primary: PrimaryFile

    @property
    def all_enums(self) -> list[EnumSpec]:
        """Enums of every file: one namespace, shared by RTDE and the primary interface."""
        return [*self.enums.enums, *self.primary_enums.enums]

    @property
    def all_bitfields(self) -> list[BitfieldSpec]:
        return [*self.enums.bitfields, *self.primary_enums.bitfields]
