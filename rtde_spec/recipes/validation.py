"""Offline recipe validation: will the controller accept this recipe, on this version?

Every problem is reported at once, each with a severity, a code, the field and a
message. The report also holds what the controller would answer to the setup
(the type list, NOT_FOUND where it would say so), so the emulator and clients
use the same rules.
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

from rtde_spec._generated.constants import DATA_PACKAGE_PREFIX_FORMAT, RTDE_ANSWERS
from rtde_spec._generated.constants import RTDE_LIMITS as LIMITS
from rtde_spec.errors import UsageError
from rtde_spec.metamodel.catalogue import Catalogue, FieldInfo
from rtde_spec.metamodel.versions import Version
from rtde_spec.recipes.files import infer_direction
from rtde_spec.recipes.model import Direction, Recipe, checked_frequency

Severity = Literal["error", "warning", "info"]
NOT_FOUND = RTDE_ANSWERS["not_found"]
# a data package: header and recipe id, then the variables
DATA_PREFIX_BYTES = struct.calcsize(DATA_PACKAGE_PREFIX_FORMAT)  # size, type, recipe id


@dataclass(frozen=True)
class Problem:
    severity: Severity
    code: str
    message: str
    field: str | None = None
    recipe: str | None = None

    def __str__(self) -> str:
        where = f"{self.recipe}: " if self.recipe else ""
        where += f"{self.field}: " if self.field else ""
        return f"{self.severity}: {where}{self.message} [{self.code}]"


@dataclass
class FieldRow:
    """One name of a recipe as the report table shows it."""

    name: str
    type: str | None
    size: int | None
    since: str
    status: Severity | Literal["ok"] = "ok"
    message: str = ""
    answer: str = NOT_FOUND


@dataclass
class RecipeReport:
    recipe: Recipe
    direction: Direction
    rows: list[FieldRow]
    problems: list[Problem]
    payload_bytes: int
    rate_divisor: int | None = None
    effective_frequency: float | None = None

    @property
    def valid(self) -> bool:
        return not any(p.severity == "error" for p in self.problems)

    @property
    def answer(self) -> list[str]:
        """The type list the controller would send back in the setup reply."""
        return [row.answer for row in self.rows]

    @property
    def label(self) -> str:
        return self.recipe.key or self.recipe.source or self.direction


@dataclass
class ValidationReport:
    controller: str | None
    line: str | None
    recipes: list[RecipeReport]
    problems: list[Problem] = field(default_factory=list)  # those spanning recipes

    @property
    def all_problems(self) -> list[Problem]:
        return [p for r in self.recipes for p in r.problems] + self.problems

    @property
    def valid(self) -> bool:
        return not any(p.severity == "error" for p in self.all_problems)


class _Checker:
    def __init__(self, catalogue: Catalogue, controller: str | None) -> None:
        self.cat = catalogue
        self.controller = controller
        self.line = catalogue.line_of(controller) if controller else None  # RecipeError if no version
        self.version = Version.parse(controller) if controller else None
        self.all_names = {d: set(catalogue.names(d)) for d in ("input", "output")}
        self.max_frequency = (
            self.line.rtde_max_frequency
            if self.line
            else max(p.rtde_max_frequency for p in catalogue.lines.values())
        )

    def suggest(self, name: str, direction: Direction) -> str:
        other: Direction = "input" if direction == "output" else "output"
        family = self._family_hint(name, direction) or self._family_hint(name, other)
        if family:
            return family
        pool = sorted(self.all_names[direction])
        import difflib

        close = difflib.get_close_matches(name, pool, n=3, cutoff=0.6)
        return f"; did you mean {', '.join(close)}?" if close else ""

    def _family_hint(self, name: str, direction: Direction) -> str:
        entries = self.cat.spec.fields.inputs if direction == "input" else self.cat.spec.fields.outputs
        for extra in self.cat.extra:
            entries = [*entries, *(extra.inputs if direction == "input" else extra.outputs)]
        for entry in entries:
            if entry.index is None:
                continue
            pattern = re.escape(entry.name).replace(re.escape("{X}"), r"(\d+)")
            match = re.fullmatch(pattern, name)
            if match:
                low, high = entry.index
                return f"; index {match.group(1)} is outside {entry.name} ({low}..{high})"
        return ""

    def unavailable(self, info: FieldInfo) -> str | None:
        if self.version is None or self.cat.available(info, self.version):
            return None
        assert self.line is not None
        first = info.since.get(self.line.id)
        others = self.cat.since_text(info)
        if first is None:
            return f"not available on {self.line.name} (available: {others})"
        return f"available from {first} on {self.line.name}; {self.controller} is older"


def _frequency(report: RecipeReport, freq: float, checker: _Checker) -> None:
    top = checker.max_frequency
    name = checker.line.name if checker.line else "any controller"
    if report.direction == "input":
        if report.recipe.frequency is not None:  # the recipe itself says so: a mistake
            report.problems.append(
                Problem("warning", "frequency-on-inputs", "a frequency applies to output recipes only")
            )
        return
    if not (1 <= freq <= top) or math.isnan(freq):
        report.problems.append(
            Problem(
                "error",
                "frequency-range",
                f"frequency {freq:g} Hz is outside 1..{top} Hz on {name}",
            )
        )
        return
    divisor = math.floor(top / freq)
    report.rate_divisor = divisor
    report.effective_frequency = top / divisor
    if not math.isclose(report.effective_frequency, freq):
        report.problems.append(
            Problem(
                "info",
                "frequency-effective",
                f"{freq:g} Hz becomes every {divisor} control cycles = "
                f"{report.effective_frequency:.4g} Hz (floor({top}/{freq:g}))",
            )
        )


def _row(
    name: str, direction: Direction, recipe: Recipe, checker: _Checker, problems: list[Problem]
) -> FieldRow:
    cat = checker.cat
    other: Direction = "input" if direction == "output" else "output"
    info = cat.get(name, direction)
    if not name:
        problems.append(Problem("error", "empty-name", "an empty name (two commas in a row?)", field=name))
        return FieldRow(name, None, None, "", "error", "empty name")
    if info is None:
        if cat.get(name, other) is not None:
            msg = f"is an {other}, not an {direction}"
            problems.append(Problem("error", "wrong-direction", msg, field=name))
        else:
            msg = "unknown field" + checker.suggest(name, direction)
            problems.append(Problem("error", "unknown-name", msg, field=name))
        return FieldRow(name, None, None, "", "error", msg)
    row = FieldRow(name, info.type, info.size, cat.since_text(info), answer=info.type)

    def flag(severity: Severity, code: str, message: str) -> None:
        problems.append(Problem(severity, code, message, field=name))
        if row.status != "error":
            row.status = severity if severity != "info" else row.status
        row.message = f"{row.message}; {message}" if row.message else message

    missing = checker.unavailable(info)
    if missing:
        row.answer = NOT_FOUND
        flag("error", "not-available", missing)
    declared = recipe.declared_types.get(name)
    if declared is not None and declared != info.type:
        flag("error", "type-mismatch", f"the recipe says {declared}, the spec says {info.type}")
    if direction == "input" and info.reserved:
        flag("warning", "reserved", f"reserved for the {info.reserved}")
    if info.deprecated:
        flag("warning", "deprecated", f"deprecated: {info.deprecated}")
    if "third-party" in info.sources and not ({"cb3-guide", "e-series-guide"} & set(info.sources)):
        flag(
            "warning",
            "undocumented",
            "not in UR's RTDE guides (used by other clients); availability is unverified",
        )
    return row


def validate_recipe(
    recipe: Recipe,
    *,
    controller: str | None = None,
    frequency: float | None = None,
    direction: Direction | None = None,
    catalogue: Catalogue | None = None,
    _checker: _Checker | None = None,
) -> RecipeReport:
    """Check one recipe; controller/frequency/direction override what the recipe says."""
    frequency = checked_frequency(frequency)
    cat = catalogue or Catalogue.default()
    checker = _checker or _Checker(cat, controller or recipe.controller)
    dirn = direction or infer_direction(recipe, checker.all_names["input"], checker.all_names["output"])
    if dirn not in ("input", "output"):
        raise UsageError(f"direction must be input or output, not {dirn!r}", subject=recipe.key)
    problems: list[Problem] = []
    rows = [_row(name, dirn, recipe, checker, problems) for name in recipe.names]
    seen: dict[str, int] = {}
    for name in recipe.names:
        seen[name] = seen.get(name, 0) + 1
    for name, count in seen.items():
        if count > 1 and name:
            problems.append(Problem("error", "duplicate", f"listed {count} times", field=name))
    if not recipe.names:
        what = "the controller needs at least one output" if dirn == "output" else "no variables"
        problems.append(Problem("error", "empty-recipe", f"empty {dirn} recipe: {what}"))
    text_bytes = len(recipe.wire_text.encode("utf-8"))
    limit, line_name = cat.setup_names_limit(checker.controller)
    bound = LIMITS["package_max_bytes"] - DATA_PREFIX_BYTES  # the uint16 size field, on every line
    if text_bytes > bound:
        problems.append(
            Problem(
                "error",
                "names-too-long",
                f"the comma-joined names take {text_bytes} bytes; a setup package holds at most {bound}",
            )
        )
    elif limit is not None and text_bytes > limit:
        # an error on the line that documents the limit; without a controller version, a warning
        severity: Severity = "error" if checker.controller else "warning"
        problems.append(
            Problem(
                severity,
                "names-too-long",
                f"the comma-joined names take {text_bytes} bytes; the limit on {line_name} is {limit}",
            )
        )
    payload = sum(row.size or 0 for row in rows)
    package = DATA_PREFIX_BYTES + payload
    if package > LIMITS["package_max_bytes"]:
        problems.append(
            Problem(
                "error",
                "package-too-large",
                f"a data package would take {package} bytes; the size field "
                f"holds at most {LIMITS['package_max_bytes']}",
            )
        )
    report = RecipeReport(recipe, dirn, rows, problems, payload)
    freq = frequency if frequency is not None else recipe.frequency
    if freq is not None:
        _frequency(report, freq, checker)
    for problem in report.problems:
        object.__setattr__(problem, "recipe", report.label)
    return report


def validate_recipes(
    recipes: Sequence[Recipe],
    *,
    controller: str | None = None,
    frequency: float | None = None,
    direction: Direction | None = None,
    catalogue: Catalogue | None = None,
) -> ValidationReport:
    """Check the recipes of one client together (e.g. all recipes of an XML file)."""
    frequency = checked_frequency(frequency)
    # names, one name or one Recipe: say so, not an AttributeError from inside
    odd = (
        recipes
        if isinstance(recipes, (str, Recipe))
        else next((r for r in recipes if not isinstance(r, Recipe)), None)
    )
    if odd is not None:
        raise UsageError(
            "validate_recipes takes a list of Recipe, e.g. [Recipe(('timestamp', 'actual_q'))], "
            f"not {type(odd).__name__} {odd!r:.60}"
        )
    cat = catalogue or Catalogue.default()
    # each recipe is checked against --controller, else the version its file names
    checkers: dict[str | None, _Checker] = {}

    def checker_for(recipe: Recipe) -> _Checker:
        version = controller or recipe.controller
        if version not in checkers:
            checkers[version] = _Checker(cat, version)
        return checkers[version]

    if len(recipes) > 1:  # name them so problems can say which one
        recipes = [r if r.key else r.with_(key=f"recipe {i + 1}") for i, r in enumerate(recipes)]
    reports = [
        validate_recipe(r, frequency=frequency, direction=direction, catalogue=cat, _checker=checker_for(r))
        for r in recipes
    ]
    cross: list[Problem] = []
    inputs = [r for r in reports if r.direction == "input"]
    owners: dict[str, list[str]] = {}
    for report in inputs:
        for name in dict.fromkeys(report.recipe.names):
            owners.setdefault(name, []).append(report.label)
    for name, labels in owners.items():
        if len(labels) > 1:
            cross.append(
                Problem(
                    "info",
                    "shared-input",
                    f"in {len(labels)} input recipes ({', '.join(labels)}): allowed, the controller "
                    "accepts a variable in several recipes of the same client",
                    field=name,
                )
            )
    if len(inputs) > LIMITS["input_recipes_max"]:
        cross.append(
            Problem(
                "error",
                "too-many-input-recipes",
                f"{len(inputs)} input recipes; the controller supports {LIMITS['input_recipes_max']}",
            )
        )
    outputs = [r for r in reports if r.direction == "output"]
    if len(outputs) > 1:
        cross.append(
            Problem(
                "warning",
                "several-output-recipes",
                f"{len(outputs)} output recipes: a controller session has one "
                "(protocol 1) or one per setup; each setup replaces the last",
            )
        )
    if None in checkers and len(checkers) > 1:
        cross.append(
            Problem(
                "warning",
                "no-controller",
                "some recipes name no controller version: their availability is not checked",
            )
        )
    if len(checkers) == 1:
        only = next(iter(checkers.values()))
        return ValidationReport(only.controller, only.line.id if only.line else None, reports, cross)
    return ValidationReport(None, None, reports, cross)


def controller_answer(
    names: Sequence[str], direction: Direction, controller: str, catalogue: Catalogue | None = None
) -> list[str]:
    """The type list a controller of this version answers to a setup of these names."""
    recipe = Recipe(tuple(names), direction=direction)
    return validate_recipe(recipe, controller=controller, catalogue=catalogue).answer
