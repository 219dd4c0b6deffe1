"""Decode a two-sided RTDE conversation, keeping the state that packages depend on.

The protocol version (from V requests) and each recipe's layout (from setup
requests and their replies) decide how later packages decode; data packages
come out as named values. The capture decoder and the demo both use this.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rtde_spec._generated import rtde_models as gen
from rtde_spec._generated.constants import RTDE_DIRECTIONS
from rtde_spec.errors import DecodeError, RecipeError
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.codec import Sender, decode, observe, setup_names
from rtde_spec.rtde.messages import RtdeMessage
from rtde_spec.rtde.protocol_state import ProtocolState
from rtde_spec.spec.catalogue import Catalogue


@dataclass
class DecodedPackage:
    sender: Sender
    message: RtdeMessage
    values: dict[str, Any] | None = None  # data packages whose recipe is known
    note: str | None = None


@dataclass
class SessionDecoder:
    """Feed whole packages in the order they crossed the wire, with their sender."""

    state: ProtocolState = field(default_factory=ProtocolState)
    catalogue: Catalogue = field(default_factory=Catalogue.default)
    _pending_names: dict[str, list[str]] = field(default_factory=dict)
    recipes: dict[tuple[str, int], RecipeCodec] = field(default_factory=dict)

    def feed(self, sender: Sender, package: bytes) -> DecodedPackage:
        message = decode(package, protocol_version=self.state.version, sender=sender)
        out = DecodedPackage(sender, message)
        observe(self.state, message)
        if isinstance(message, (gen.SetupOutputsV1, gen.SetupOutputsV2)):
            self._pending_names["output"] = setup_names(message.variable_names)
        elif isinstance(message, gen.SetupInputs):
            self._pending_names["input"] = setup_names(message.variable_names)
        elif isinstance(message, (gen.SetupOutputsV1Reply, gen.SetupOutputsV2Reply)):
            recipe_id = getattr(message, "output_recipe_id", 1)
            self._learn("output", recipe_id, message.variable_types, out)
        elif isinstance(message, gen.SetupInputsReply):
            self._learn("input", message.input_recipe_id, message.variable_types, out)
        elif isinstance(message, gen.DataPackage):
            direction = RTDE_DIRECTIONS[sender]
            codec = self.recipes.get((direction, message.recipe_id))
            if codec is None:
                out.note = f"no {direction} recipe {message.recipe_id} was set up"
            else:
                try:
                    out.values = codec.decode(message.payload)
                except DecodeError as exc:
                    out.note = str(exc)
        return out

    @property
    def protocol_version(self) -> int:
        return self.state.version

    def _learn(self, direction: str, recipe_id: int, types: list[str], out: DecodedPackage) -> None:
        names = self._pending_names.pop(direction, None)
        if names is None or recipe_id == 0:
            out.note = "recipe rejected" if recipe_id == 0 else "reply without a request"
            return
        try:
            self.recipes[(direction, recipe_id)] = RecipeCodec.for_types(names, types, self.catalogue)
        except RecipeError as exc:
            out.note = str(exc)
