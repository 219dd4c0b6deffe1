"""A recipe: the ordered variables a client subscribes to (outputs) or writes (inputs)."""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any, Literal

from rtde_spec.errors import RecipeError, UsageError

Direction = Literal["input", "output"]
FILE_FORMATS = ("xml", "lines", "csv", "yaml", "json")
"""Recipe file formats that `recipes.files` reads and writes."""


@dataclass(frozen=True)
class Recipe:
    """Ordered names plus what a file may say about them.

    `declared_types` holds types written in the file (UR's XML format has them);
    validation checks them against the spec. `key` names the recipe in files that
    hold several. `direction` None means: infer it from the names.
    """

    names: tuple[str, ...]
    direction: Direction | None = None
    frequency: float | None = None
    controller: str | None = None
    key: str | None = None
    declared_types: dict[str, str] = field(default_factory=dict)
    source: str | None = None

    def __post_init__(self) -> None:
        """Names as a tuple of text: a list is taken, one string is the comma list (it was read a
        character a name), a name that is no text is a UsageError (not a TypeError from inside)."""
        object.__setattr__(self, "names", recipe_names(self.names))

    @classmethod
    def parse(cls, text: str, direction: Direction | None = None) -> Recipe:
        """A comma list, as the setup package carries it ("timestamp,actual_q")."""
        names = [n.strip() for n in text.split(",")]
        if len(names) > 1 and names[-1] == "":
            names.pop()  # a trailing comma, as ur_rtde sends it
        return cls(tuple(names), direction=direction)

    def with_(self, **changes: object) -> Recipe:
        return replace(self, **changes)  # type: ignore[arg-type]

    @property
    def wire_text(self) -> str:
        """The names as the setup package carries them."""
        return ",".join(self.names)


def recipe_names(names: Iterable[str] | str) -> tuple[str, ...]:
    """The names a client subscribes to, taken once: a generator would be used up by the offline
    check before the setup request, and one string is read as the setup package's comma list
    ("timestamp,actual_q"), not as one name a character."""
    if isinstance(names, str):
        return Recipe.parse(names).names
    if isinstance(names, (bytes, bytearray)) or not isinstance(names, Iterable):
        raise UsageError(f"recipe names must be a list of names, not {type(names).__name__} {names!r:.80}")
    taken = tuple(names)
    odd = [n for n in taken if not isinstance(n, str)]
    if odd:
        raise UsageError(f"recipe names must be text: {odd[0]!r} is a {type(odd[0]).__name__}")
    return taken


def checked_frequency(frequency: Any, *, required: bool = False) -> float | None:
    """`frequency` as a float, or UsageError naming it: a str or a bool is no rate in Hz; None
    is "not given", unless `required` (a client's setup request carries a rate)."""
    if frequency is None and not required:
        return None
    if isinstance(frequency, (str, bytes, bool)) or not isinstance(frequency, numbers.Real):
        raise UsageError(
            f"frequency must be a number of Hz, not {type(frequency).__name__} {frequency!r:.80}"
        )
    return float(frequency)


def check_savable(recipes: list[Recipe]) -> None:
    """RecipeError for what a recipe file cannot hold and read back: no recipe at all (a file
    load_recipes refuses), a rate that is no finite number (JSON's NaN, YAML's .inf)."""
    if not recipes:
        raise RecipeError("no recipes to write: a recipe file holds at least one")
    for recipe in recipes:
        if recipe.frequency is not None and not math.isfinite(recipe.frequency):
            raise RecipeError(
                "frequency must be a finite number of Hz", subject=recipe.key, actual=recipe.frequency
            )
