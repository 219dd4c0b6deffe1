"""Decode a two-sided RTDE conversation, keeping the state that packages depend on.

The protocol version (from V requests) and each recipe's layout (from setup
requests and their replies) decide how later packages decode; data packages
come out as named values. The capture decoder and the demo both use this.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

from rtde_spec._generated.constants import RTDE_DIRECTIONS
from rtde_spec.errors import DecodeError, RecipeError
from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.recipes.codec import RecipeCodec
from rtde_spec.rtde.data_forms import implied_recipe_id, lacks_recipe_id, with_recipe_id
from rtde_spec.rtde.packages import (
    DATA,
    SETUP_REPLIES,
    SETUP_REQUESTS,
    Package,
    Sender,
    decode_package,
    observe_package,
    setup_names,
)
from rtde_spec.rtde.protocol_state import ProtocolState

if TYPE_CHECKING:
    from rtde_spec.wire.rtde_messages import RtdeMessage


@dataclass
class DecodedPackage:
    sender: Sender
    package: Package  # name and values, from the layout engine
    values: dict[str, Any] | None = None  # data packages whose recipe is known
    note: str | None = None
    problem: str | None = None  # a package that breaks the protocol (a setup reply that fits no request)

    @cached_property
    def message(self) -> RtdeMessage:
        """The package as its pydantic model (the models load with the first one asked for)."""
        from rtde_spec.rtde.codec import model_of

        return model_of(self.package.name, self.package.values)


@dataclass
class SessionDecoder:
    """Feed whole packages in the order they crossed the wire, with their sender."""

    state: ProtocolState = field(default_factory=ProtocolState)
    catalogue: Catalogue = field(default_factory=Catalogue.default)
    _pending_names: dict[str, list[str]] = field(default_factory=dict)
    recipes: dict[tuple[str, int], RecipeCodec] = field(default_factory=dict)

    def guide_form(self, sender: str, package: bytes | bytearray | memoryview) -> bytes | None:
        """A data package sent without its recipe id (protocol 1 allows it: `data_forms`), in the
        guides' form with the implied id; None when `package` is not one."""
        implied = implied_recipe_id(sender, self.state.version)
        if implied is None:
            return None
        codec = self.recipes.get((RTDE_DIRECTIONS[sender], implied))
        if codec is None or not lacks_recipe_id(package, codec.size):
            return None
        return with_recipe_id(package, implied)

    def feed(self, sender: Sender, package: bytes) -> DecodedPackage:
        whole = self.guide_form(sender, package)
        if whole is not None:
            package = whole
        decoded = decode_package(package, protocol_version=self.state.version, sender=sender)
        name, values = decoded.name, decoded.values
        out = DecodedPackage(sender, decoded)
        if whole is not None:
            out.note = f"sent without its recipe id byte: recipe {values['recipe_id']} by its size"
        observe_package(self.state, name, values)
        if name in SETUP_REQUESTS:
            self._pending_names[SETUP_REQUESTS[name]] = setup_names(values["variable_names"])
        elif name in SETUP_REPLIES:
            direction = SETUP_REPLIES[name]
            recipe_id = values.get(f"{direction}_recipe_id", 1)  # protocol 1 has one output recipe
            self._learn(direction, recipe_id, values["variable_types"], out)
        elif name == DATA:
            direction = RTDE_DIRECTIONS[sender]
            codec = self.recipes.get((direction, values["recipe_id"]))
            if codec is None:
                out.note = f"no {direction} recipe {values['recipe_id']} was set up"
            else:
                try:
                    out.values = codec.decode(values["payload"])
                except DecodeError as exc:
                    out.note = str(exc) if out.note is None else f"{out.note}; {exc}"
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
            self.recipes[(direction, recipe_id)] = shared_codec(names, types, self.catalogue)
        except RecipeError as exc:
            out.note = out.problem = str(exc)


_CODECS: dict[tuple[int, tuple[str, ...], tuple[str, ...]], tuple[Any, RecipeCodec]] = {}


def shared_codec(names: Sequence[str], types: Sequence[str], catalogue: Any) -> RecipeCodec:
    """The codec of a setup exchange, compiled once per recipe: a capture of 50,000 connections that
    all set up the same recipe compiles it once, not 50,000 times (a codec holds no state)."""
    key = (id(catalogue), tuple(names), tuple(types))
    found = _CODECS.get(key)
    if found is not None and found[0] is catalogue:
        return found[1]
    codec = RecipeCodec.for_types(names, types, catalogue)
    if len(_CODECS) >= 256:
        _CODECS.clear()
    _CODECS[key] = (catalogue, codec)
    return codec
