"""The meta-model of spec/arms/models.yaml: one UR arm's nominal geometry and limits.

The emulator's kinematics and the kinematics sub-package read these; codegen
writes the validated file to `_generated/arms.py`, so the installed package needs
no YAML. Unknown keys, a row that is not six values, or a name given twice are
errors naming the file, the entry and the line.
"""

from __future__ import annotations

import math
from functools import cache
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, model_validator

from rtde_spec.errors import UsageError
from rtde_spec.metamodel.schema import StrictModel

SPEC_FILE = "arms/models.yaml"
Six = Annotated[tuple[float, float, float, float, float, float], Field()]


class DhTable(StrictModel):
    """Standard Denavit-Hartenberg rows (theta offsets 0): a and d in m, alpha in rad."""

    a: Six
    d: Six
    alpha: Six


class ArmModel(StrictModel):
    name: Annotated[str, Field(pattern=r"^UR\d+e?$")]
    line: Literal["cb3", "e-series"]
    doc: str
    source: str
    checked: bool
    dh: DhTable
    joint_range_deg: Six
    joint_speed_deg_s: Six | None = None
    payload_kg: Annotated[float, Field(gt=0)]
    reach_m: Annotated[float, Field(gt=0)]
    controller_box_type: Annotated[int, Field(ge=0, le=2**31 - 1)] | None = None  # Configuration Data
    robot_sub_type: Annotated[int, Field(ge=0, le=2**31 - 1)] = 0  # Configuration Data: the series

    @property
    def joint_limits(self) -> tuple[tuple[float, float], ...]:
        """(low, high) in rad per joint."""
        return tuple((-math.radians(r), math.radians(r)) for r in self.joint_range_deg)

    @property
    def max_joint_speed(self) -> tuple[float, ...]:
        """rad/s per joint; 180 deg/s where no speed is published."""
        return tuple(math.radians(v) for v in (self.joint_speed_deg_s or (180.0,) * 6))


class ArmsFile(StrictModel):
    models: list[ArmModel]

    @model_validator(mode="after")
    def _unique(self) -> ArmsFile:
        seen: set[str] = set()
        for m in self.models:
            if m.name.lower() in seen:
                raise ValueError(f"arm model {m.name!r} is given twice")
            seen.add(m.name.lower())
        return self


def load_arms(root: Path | str) -> ArmsFile:
    """Load and validate arms/models.yaml below spec root `root`; SpecError names every problem."""
    from rtde_spec.metamodel.loader import load_file

    return load_file(root, SPEC_FILE, ArmsFile)


@cache
def arm_models() -> dict[str, ArmModel]:
    """The built-in arm models by lower-case name, from the generated table."""
    from rtde_spec._generated.arms import ARMS

    return {m.name.lower(): m for m in ArmsFile.model_validate(ARMS).models}


def arm_model(name: str) -> ArmModel:
    """One arm by name, case-insensitive (`ur5e`, `UR5e`); UsageError lists the known ones."""
    found = arm_models().get(name.strip().lower())
    if found is None:
        known = ", ".join(m.name for m in arm_models().values())
        raise UsageError(f"unknown arm model {name!r} (known: {known})", subject="arm model")
    return found
