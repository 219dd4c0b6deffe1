"""What generated pydantic models share: the wire's string rules, and the models' config."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, ConfigDict, Field, PlainSerializer

# Every protocol message model's config. Frozen, no unknown keys. Schemas are built on first
# use: a capture or decode imports ~100 classes and uses a few. Bytes are hex in JSON: protocol
# bytes (extra, raw, data) are rarely UTF-8. NaN and infinities are "NaN", "Infinity": valid
# JSON that reads back (pydantic's null did not).
WIRE_MODEL_CONFIG = ConfigDict(
    extra="forbid",
    frozen=True,
    defer_build=True,
    ser_json_bytes="hex",
    val_json_bytes="hex",
    ser_json_inf_nan="strings",
)


def _ascii(value: str) -> str:
    if not value.isascii():
        bad = next(i for i, ch in enumerate(value) if not ch.isascii())
        raise ValueError(f"not ASCII: {value[bad]!r} at character {bad}")
    return value


def _csv_item(value: str) -> str:
    if "," in value:
        raise ValueError(f"{value!r} contains a comma, the list separator")
    return _ascii(value)


AsciiStr = Annotated[str, AfterValidator(_ascii)]
"""A string that runs to the end of the package."""

ShortAsciiStr = Annotated[str, Field(max_length=255), AfterValidator(_ascii)]
"""A string behind a uint8 length prefix."""

CsvItem = Annotated[str, AfterValidator(_csv_item)]
"""One name of a comma-separated list."""


def json_text(value: str) -> str:
    """Text for JSON: bytes that were not UTF-8 on the wire as `\\xNN` escapes.

    The decoders keep such bytes as surrogate escapes, so encoding gives the wire's bytes
    back; JSON cannot hold lone surrogates (pydantic refuses them), so a dump shows them
    as Python's backslashreplace does.
    """
    if value.isascii():
        return value
    return value.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


WireText = Annotated[str, PlainSerializer(json_text, return_type=str, when_used="json")]
"""Primary-interface text: UTF-8, any bytes kept (surrogate escapes), escaped in JSON."""
