"""Scenario files: the version the emulated controller reports and how its outputs move.

A scenario is YAML, validated with pydantic so a typo is an error naming the file,
the key and why:

    controller: 5.15.0
    outputs:
      actual_q: {sine: {amplitude: 0.5, period: 4.0, offset: [0, -1.57, 1.57, 0, 0, 0]}}
      robot_mode: 7
      output_double_register_24: {ramp: {rate: 0.1}}

A value is a constant (number, bool or list for vectors) or one function of time:
`sine` (amplitude, period in s, phase in rad, offset; each a number or a list per
element) or `ramp` (start, rate per second). `faults` schedules a protective stop,
emergency stop, power loss, program stop or network drop at a time (faults.py):

    faults:
      - {at: 2.0, fault: protective_stop}
      - {at: 5.0, fault: network_drop, seconds: 3}

`calibrated: false` makes the arm report no kinematics calibration (Kinematics Info's
calibration status 0, as a URSim reports), for testing a driver's calibration check.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from rtde_spec.emulator.controller.faults import Fault
from rtde_spec.errors import UsageError
from rtde_spec.metamodel import safe_yaml
from rtde_spec.metamodel.catalogue import Catalogue

Number = float | list[float]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Sine(_Strict):
    amplitude: Number = 1.0
    period: float = Field(1.0, gt=0)
    phase: Number = 0.0
    offset: Number = 0.0


class Ramp(_Strict):
    start: Number = 0.0
    rate: Number = 1.0


class SineOf(_Strict):
    sine: Sine


class RampOf(_Strict):
    ramp: Ramp


class Scenario(_Strict):
    controller: str = "5.15.0"
    outputs: dict[str, bool | int | float | list[float] | SineOf | RampOf] = {}
    faults: list[Fault] = []  # what goes wrong, when (faults.py)
    calibrated: bool = True  # False: Kinematics Info says the arm has no calibration (as URSim's)

    def functions(self, catalogue: Catalogue) -> dict[str, Callable[[float], Any]]:
        """Output name -> value at time t (s); names and lengths checked against the spec."""
        catalogue.line_of(self.controller)
        out: dict[str, Callable[[float], Any]] = {}
        for name, spec in self.outputs.items():
            info = catalogue.get(name, "output")
            if info is None:
                raise UsageError(f"unknown output {name!r}", subject="scenario")
            count = info.wire.count
            out[name] = _function(name, spec, count, info.wire.kind, info.wire.bounds)
        return out


def _per_element(name: str, value: Number, count: int) -> list[float]:
    if isinstance(value, list):
        if len(value) != count:
            raise UsageError(f"{name}: needs {count} values, got {len(value)}", subject="scenario")
        return [float(v) for v in value]
    return [float(value)] * count


def _function(
    name: str, spec: Any, count: int, kind: str, bounds: tuple[int, int] | None
) -> Callable[[float], Any]:
    low, high = bounds or (0, 0)

    def to_int(v: float) -> int:
        return min(max(round(v), low), high)  # an integer output stays within its wire type

    casts: dict[str, Callable[[float], Any]] = {"int": to_int, "bool": bool, "float": float}
    cast = casts[kind]
    if isinstance(spec, SineOf):
        s = spec.sine
        amp, phase, off = (_per_element(name, v, count) for v in (s.amplitude, s.phase, s.offset))
        omega = 2 * math.pi / s.period

        def sine(t: float) -> Any:
            vals = [cast(o + a * math.sin(omega * t + p)) for a, p, o in zip(amp, phase, off, strict=True)]
            return vals[0] if count == 1 else tuple(vals)

        return sine
    if isinstance(spec, RampOf):
        start, rate = (_per_element(name, v, count) for v in (spec.ramp.start, spec.ramp.rate))

        def ramp(t: float) -> Any:
            vals = [cast(s0 + r * t) for s0, r in zip(start, rate, strict=True)]
            return vals[0] if count == 1 else tuple(vals)

        return ramp
    if count > 1:
        const: Any = tuple(cast(v) for v in _per_element(name, spec, count))
    elif isinstance(spec, list):
        raise UsageError(f"{name}: a single value, not a list", subject="scenario")
    else:
        const = cast(spec)
    return lambda t: const


def load_scenario(path: str | Path) -> Scenario:
    """A scenario from YAML; every problem is a UsageError naming the file and key."""
    try:
        data = safe_yaml.load(Path(path).read_text(encoding="utf-8")) or {}
    except UnicodeDecodeError as exc:
        said = f"not UTF-8 text: byte 0x{exc.object[exc.start]:02x} at offset {exc.start}"
        raise UsageError(f"cannot read scenario: {said}", subject=f"file {path}") from None
    except (OSError, yaml.YAMLError) as exc:
        raise UsageError(f"cannot read scenario: {exc}", subject=f"file {path}") from None
    if not isinstance(data, dict):
        said = f"a scenario is a mapping ({', '.join(Scenario.model_fields)}), not {_kind(data)}"
        raise UsageError(said, subject=f"scenario file {path}")
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise UsageError(_explained(exc, data), subject=f"scenario file {path}") from None


SHAPES = {"sine": "SineOf", "ramp": "RampOf"}  # an output's function, as the union names its member
MEMBERS = {*SHAPES.values(), "bool", "int", "float", "list[float]"}  # tags, not keys of the file
VALUES = "a number, true or false, a list of numbers, {sine: {...}} or {ramp: {...}}"


def _explained(exc: ValidationError, data: dict[str, Any]) -> str:
    """The error of the value's own shape: pydantic lists one per member of an output's union,
    first "Input should be a valid boolean" for a sine whose period is 0."""
    errors = exc.errors()
    first = errors[0]
    loc = first["loc"]
    if len(loc) >= 3 and loc[0] == "outputs":
        name = loc[1]
        outputs = data.get("outputs")
        value = outputs.get(name) if isinstance(outputs, dict) else None
        shape = next((SHAPES[k] for k in SHAPES if isinstance(value, dict) and k in value), None)
        if shape is None:
            return f"outputs.{name}: {safe_repr(value)} is not {VALUES}"
        first = next(e for e in errors if e["loc"][:3] == ("outputs", name, shape))
        loc = first["loc"]
    return f"{'.'.join(str(p) for p in loc if p not in MEMBERS)}: {first['msg']}"


def _kind(data: object) -> str:
    return "a list" if isinstance(data, list) else f"{safe_repr(data)}"


def safe_repr(value: object) -> str:
    """A value as the file gave it, cut short: a scenario may hold a long list by mistake."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."
