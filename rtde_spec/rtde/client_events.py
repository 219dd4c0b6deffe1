"""What the RTDE client core hands out and keeps: requests, replies, runs of data packages, texts.

Plain data, apart from the sans-I/O core (`client_protocol`) that makes them, so the
blocking and asyncio clients and their users can name them without the core.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rtde_spec.errors import RtdeSpecError
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.packages import Package


@dataclass(frozen=True)
class InputRecipe:
    """An accepted input recipe: send values for its names with `recipe_id`."""

    recipe_id: int
    names: tuple[str, ...]
    codec: RecipeCodec


@dataclass(eq=False)
class Request:
    """A request sent and waiting for its reply, which carries the same package type."""

    name: str  # the request's spec name, e.g. "setup_outputs_v2"
    package_type: int
    message: Package
    setup: tuple[str, tuple[str, ...]] | None = None  # (direction, names) of a setup request
    others: list[str] = field(default_factory=list)  # replies of other types that came meanwhile


@dataclass(frozen=True)
class Reply:
    """The controller's answer to a request (version, setup, start, pause); `error` if refused."""

    message: Package
    error: RtdeSpecError | None = None
    request: Request | None = None  # the request it answers


@dataclass(frozen=True)
class DataRun:
    """Data packages of the output recipe that came back to back (one or more), as records
    (an empty list when the core was told no one wants them: `ClientProtocol.want_records`)."""

    records: list[Any]
    raw: bytes | memoryview  # the packages, back to back, in the guides' form (with the id: data_forms)
    size: int  # bytes per package

    @property
    def count(self) -> int:
        return len(self.raw) // self.size

    def packages(self) -> list[bytes]:
        """Each package's bytes."""
        raw, size = self.raw, self.size
        return [bytes(raw[at : at + size]) for at in range(0, len(raw), size)]


@dataclass(frozen=True)
class Text:
    """A text message from the controller."""

    level: int
    message: str
    source: str


Event = Reply | DataRun | Text
