"""A one-sided RTDE byte stream, fed in chunks, out as packages and batches of data packages.

Data packages of the recipe that arrive back to back are decoded together
(`RecipeCodec.decode_many`: one numpy view, one prefix check), everything else one
package at a time by the generic codec; the order of the stream is kept. Offsets
are absolute in the stream, and every error names the package it is in.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from rtde_spec._generated import rtde_models as gen
from rtde_spec.errors import DecodeError
from rtde_spec.recipes.codec import PAYLOAD_OFFSET, RecipeCodec
from rtde_spec.rtde.codec import Sender, decode, observe, starting_version
from rtde_spec.rtde.messages import RtdeMessage
from rtde_spec.rtde.protocol_state import ProtocolState
from rtde_spec.wire.framing import PackageFramer

DATA = gen.DataPackage.PACKAGE_TYPE
_HEADER = struct.Struct(gen.HEADER_FORMAT)


@dataclass
class Package:
    """One package; `values` holds a data package's fields when a recipe decodes it."""

    offset: int
    message: RtdeMessage
    values: dict[str, Any] | None = None


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
    ) -> None:
        self.sender = sender
        self.codec = codec
        self.strict = strict
        self.state = ProtocolState(one_sided=True)
        self._given_version = protocol_version
        self._started = False
        self._framer = PackageFramer()
        self._run: tuple[int, bytes] | None = None  # (package size, header bytes) of batched packages
        if batch and codec is not None and _has_numpy():
            self._run = (codec.package_size, _HEADER.pack(codec.package_size, DATA))
        self.packages = 0

    def feed(self, data: bytes | bytearray | memoryview) -> Iterator[Package | Batch]:
        """Items for every package this data completes, in stream order."""
        for offset, chunk in self._framer.feed(data, self._run):
            if not self._started:
                self.state.version = starting_version(chunk, self._given_version)
                self._started = True
            run = self._run
            if run is not None and len(chunk) >= run[0] and bytes(chunk[: len(run[1])]) == run[1]:
                yield self._batch_of(offset, chunk)
            else:
                yield self._one(offset, chunk)

    def close(self) -> None:
        """DecodeError if the stream ended inside a package."""
        self._framer.close()

    def _batch_of(self, offset: int, run: bytes | memoryview) -> Batch:
        assert self.codec is not None
        try:
            array = self.codec.decode_many(run)
        except DecodeError as exc:
            raise exc.in_stream(offset, self.packages + 1) from None
        self.packages += len(array)
        return Batch(offset, array)

    def _one(self, offset: int, package: bytes) -> Package:
        self.packages += 1
        try:
            message = decode(
                package, protocol_version=self.state.version, sender=self.sender, strict=self.strict
            )
        except DecodeError as exc:
            raise exc.in_stream(offset, self.packages) from None
        observe(self.state, message)
        values = None
        if self.codec is not None and isinstance(message, gen.DataPackage):
            try:
                values = self.codec.decode(message.payload)
            except DecodeError as exc:
                raise exc.in_stream(offset, self.packages) from None
        return Package(offset, message, values)


def _has_numpy() -> bool:
    try:
        import numpy  # noqa: F401
    except ImportError:
        return False
    return True


__all__ = ["PAYLOAD_OFFSET", "Batch", "Package", "StreamDecoder"]
