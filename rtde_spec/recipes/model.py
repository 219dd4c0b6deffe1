"""A recipe: the ordered variables a client subscribes to (outputs) or writes (inputs)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Literal

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
