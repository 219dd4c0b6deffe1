"""Annotated types shared by generated pydantic models: the wire's string rules."""

from __future__ import annotations

from typing import Annotated

from pydantic import AfterValidator, Field


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
