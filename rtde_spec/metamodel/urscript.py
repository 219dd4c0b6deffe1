"""The meta-model of spec/urscript/functions.yaml: URScript's built-in functions.

Each function has its parameters in order (those with a default may be left out), what it
returns, the first version per product line and the Script Manual module it is in. The
emulator's interpreter implements exactly these (a test holds it); codegen writes the table
to `_generated/urscript_functions.py` and docs/reference/urscript.md. Unknown keys, a function
or parameter given twice, a required parameter after an optional one, or an unknown product
line are errors naming the file and the entry.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from rtde_spec.metamodel.schema import Since, StrictModel

SPEC_FILE = "urscript/functions.yaml"
ValueType = Literal["none", "bool", "int", "float", "number", "string", "pose", "array", "struct", "handle"]
Section = Literal["motion", "internals", "interfaces", "worldmodel", "maths"]
Name = Annotated[str, Field(pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")]


class Parameter(StrictModel):
    name: Name
    default: Any = None  # None: the parameter must be given

    @property
    def required(self) -> bool:
        return "default" not in self.model_fields_set


class ScriptFunction(StrictModel):
    name: Name
    section: Section
    params: list[Parameter] = Field(default_factory=list)
    returns: ValueType
    since: Since
    checked: bool = True  # False: `since` is the product line's first release, not the manual's word
    doc: str
    emulation: str | None = None  # how the emulator approximates what it cannot do physically

    @model_validator(mode="after")
    def _params_in_order(self) -> ScriptFunction:
        seen: set[str] = set()
        optional = False
        for p in self.params:
            if p.name in seen:
                raise ValueError(f"{self.name}: parameter {p.name!r} is given twice")
            seen.add(p.name)
            if optional and p.required:
                raise ValueError(f"{self.name}: required parameter {p.name!r} after an optional one")
            optional = optional or not p.required
        return self


class ScriptFunctions(StrictModel):
    doc_ref: str
    product_lines: list[Literal["cb3", "e-series", "polyscope-x"]]
    interpreter_port: Annotated[int, Field(ge=1, le=65535)] | None = None  # interpreter mode's socket
    functions: list[ScriptFunction]

    @model_validator(mode="after")
    def _unique(self) -> ScriptFunctions:
        seen: set[str] = set()
        for f in self.functions:
            if f.name in seen:
                raise ValueError(f"function {f.name!r} is given twice")
            seen.add(f.name)
            unknown = set(f.since) - set(self.product_lines)
            if unknown:
                raise ValueError(f"{f.name}: since names {sorted(unknown)}, not a product line of the file")
        return self


def load_urscript(root: Path | str) -> ScriptFunctions:
    """Load and validate urscript/functions.yaml below spec root `root`; SpecError says what is wrong."""
    from rtde_spec.metamodel.loader import load_file

    return load_file(root, SPEC_FILE, ScriptFunctions)


@cache
def urscript_functions() -> ScriptFunctions:
    """The built-in table, from the generated module."""
    from rtde_spec._generated.urscript_functions import URSCRIPT_FUNCTIONS

    return ScriptFunctions.model_validate(URSCRIPT_FUNCTIONS)
