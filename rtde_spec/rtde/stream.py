"""A one-sided RTDE byte stream, fed in chunks, out as packages and batches of data packages.

Data packages of the recipe that arrive back to back are decoded together
(`RecipeCodec.decode_many`: one numpy view, one prefix check), everything else one
package at a time by the generic codec; the order of the stream is kept. Offsets
are absolute in the stream, and every error names the package it is in.

Nothing decoded is lost to a later fault: a feed that meets an unusable size
yields every package before it, then raises. With `skip_errors` (the CLI's
--lenient), a package that is framed but does not decode (an unknown type, a
payload shorter than the recipe) is skipped and counted in `skipped` instead.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec
from rtde_spec.recipes.encoding import PREFIX, expected_recipe_id
from rtde_spec.rtde.codec import Sender, decode, observe, starting_version
from rtde_spec.rtde.data_forms import implied_recipe_id, lacks_recipe_id, with_recipe_id
from rtde_spec.rtde.protocol_state import ProtocolState
from rtde_spec.wire.framing import PackageFramer, Skipped
from rtde_spec.wire.rtde_messages import RtdeMessage

DATA = gen.DataPackage.PACKAGE_TYPE
ID_AT = PREFIX.size - struct.calcsize(PREFIX.format[0] + PREFIX.format[-1])  # the recipe id in a package
_HEADER = struct.Struct(gen.HEADER_FORMAT)


@dataclass
class Package:
    """One package; `values` holds a data package's fields when a recipe decodes it."""

    offset: int
    message: RtdeMessage
    values: dict[str, Any] | None = None
    without_recipe_id: bool = False  # sent without its id byte (protocol 1): `message` has the implied id


@dataclass
class Batch:
    """Data packages of the recipe, back to back from `offset`: a numpy structured array."""

    offset: int
    array: Any


class StreamDecoder:
    """Feed bytes as they come; get Package and Batch items in stream order."""

    def __init__(
        self,
        sender: Sender = "controller",
        *,
        protocol_version: int | None = None,
        codec: RecipeCodec | None = None,
        strict: bool = True,
        batch: bool = True,
        skip_errors: bool = False,
        recipe_id: int | None = None,
    ) -> None:
        """`codec` decodes the data packages of one recipe: those of `recipe_id`, the others pass
        undecoded (`values` None). Without `recipe_id`, the recipe of the first data package; a
        data package of another recipe is then a DecodeError (or skipped with `skip_errors`):
        decoded with the codec of another recipe of the same size, it gave wrong numbers."""
        self.sender = sender
        self.codec = codec
        self.chosen = recipe_id is not None  # by the caller: other recipes pass undecoded
        self.recipe_id = None if recipe_id is None else expected_recipe_id(recipe_id)
        self.strict = strict
        self.skip_errors = skip_errors
        self.skipped = Skipped()
        self.state = ProtocolState(one_sided=True)
        self._given_version = protocol_version
        self._started = False
        self._framer = PackageFramer()
        self._run: tuple[int, bytes] | None = None  # (package size, header bytes) of batched packages
        if batch and codec is not None and _has_numpy():
            self._run = (codec.package_size, _HEADER.pack(codec.package_size, DATA))
            if self.recipe_id is not None:
                self._pin(self.recipe_id)
        self.packages = 0

    def feed(self, data: bytes | bytearray | memoryview) -> Iterator[Package | Batch]:
        """Items for every package this data completes, in stream order.

        A size that cannot be framed raises after the packages before it are yielded.
        """
        failure: DecodeError | None = None
        try:
            framed = self._framer.feed(data, self._run)
        except DecodeError as exc:
            framed, failure = self._framer.salvaged, exc
        for offset, chunk in framed:
            if not self._started:
                self.state.version = starting_version(chunk, self._given_version)
                self._started = True
            run = self._run
            if run is not None and len(chunk) >= run[0] and bytes(chunk[: len(run[1])]) == run[1]:
                yield from self._batch_of(offset, chunk)
            else:
                item = self._one(offset, chunk)
                if item is not None:
                    yield item
        if failure is not None:
            raise failure

    @property
    def unframed(self) -> int:
        """Bytes held that are not (yet) a package: after a framing fault, those from the fault on."""
        return self._framer.pending

    def close(self) -> None:
        """DecodeError if the stream ended inside a package (or could not be framed)."""
        self._framer.close()

    def _pin(self, recipe_id: int) -> None:
        """Data packages of `recipe_id` are the codec's: runs of them are batched, no other."""
        self.recipe_id = recipe_id
        if self._run is not None:
            self._run = (self._run[0], PREFIX.pack(self._run[0], DATA, recipe_id))

    def _batch_of(self, offset: int, run: bytes | memoryview) -> Iterator[Batch | Package]:
        assert self.codec is not None
        if self.recipe_id is None:
            self._pin(PREFIX.unpack_from(run)[2])  # the first data package's recipe
        try:
            array = self.codec.decode_many(run, self.recipe_id)
        except DecodeError:  # one at a time: those before the bad one kept, it said (or skipped)
            size = self.codec.package_size
            for at in range(0, len(run), size):
                item = self._one(offset + at, bytes(run[at : at + size]))
                if item is not None:
                    yield item
            return
        self.packages += len(array)
        yield Batch(offset, array)

    def _one(self, offset: int, package: bytes) -> Package | None:
        """The package decoded; None when it does not decode and errors are skipped."""
        self.packages += 1
        whole = self._with_recipe_id(package)
        if whole is not None:
            package = whole
        try:
            message = decode(
                package, protocol_version=self.state.version, sender=self.sender, strict=self.strict
            )
            values = None
            if self.codec is not None and isinstance(message, gen.DataPackage) and self._ours(message):
                payload = message.payload
                if not self.strict and len(payload) > self.codec.size:  # newer firmware appended fields
                    payload = payload[: self.codec.size]
                try:
                    values = self.codec.decode(payload)
                except DecodeError as exc:  # payload offsets, seen from the package's start
                    raise exc.relocated(len(package) - len(message.payload)) from None
        except DecodeError as exc:
            if not self.skip_errors:
                raise exc.in_stream(offset, self.packages) from None
            self.skipped.add(offset, len(package), str(exc.in_stream(offset, self.packages)))
            return None
        observe(self.state, message)
        return Package(offset, message, values, whole is not None)

    def _ours(self, message: gen.DataPackage) -> bool:
        """Whether the codec decodes this data package: one of its recipe (the first one's, unless
        the caller chose). Another recipe's is passed undecoded if the caller chose, else refused."""
        rid = message.recipe_id
        if self.recipe_id is None:
            self._pin(rid)
        if rid == self.recipe_id:
            return True
        if self.chosen:
            return False
        raise DecodeError(
            f"a data package of recipe {rid} after those of recipe {self.recipe_id}: the recipe given "
            "decodes one recipe's packages (StreamDecoder(recipe_id=...) says which; --lenient skips the "
            "rest)",
            package="data_package",
            field="recipe_id",
            offset=ID_AT,
            expected=self.recipe_id,
            actual=rid,
        )

    def _with_recipe_id(self, package: bytes | memoryview) -> bytes | None:
        """The guides' form of a data package of the recipe sent without its id byte (where the
        protocol allows it, told by its size: `data_forms`); None for every other package."""
        implied = implied_recipe_id(self.sender, self.state.version)
        if implied is None or self.codec is None or not lacks_recipe_id(package, self.codec.size):
            return None
        return with_recipe_id(package, implied)


def _has_numpy() -> bool:
    try:
        import numpy  # noqa: F401
    except ImportError:
        return False
    return True


__all__ = ["PAYLOAD_OFFSET", "Batch", "Package", "Skipped", "StreamDecoder"]
