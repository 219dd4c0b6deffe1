"""Printing decoded primary/secondary messages: a readable tree or JSON by spec names, as they arrive."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel

from rtde_spec.capture.tables.rows import RAW, text_columns
from rtde_spec.cli.report import close_output, report_skipped
from rtde_spec.errors import DecodeError, RtdeSpecError
from rtde_spec.output.describe import describe
from rtde_spec.output.text import safe_text
from rtde_spec.output.writers import open_writer
from rtde_spec.primary.codec import PrimaryStreamDecoder
from rtde_spec.wire.primary_base import PrimaryPart, RobotStateMessage

if TYPE_CHECKING:
    from rtde_spec.output.base import Writer


def as_json(value: Any) -> Any:
    """Models as dicts keyed by field name (bookkeeping fields only when set).

    Text that is not UTF-8 (kept by the decoder as surrogate escapes, which no JSON, CSV
    or MCAP writer takes) reads as in capture tables: U+FFFD where the bytes are not
    UTF-8, and the bytes in hex in a `<name>_raw` key beside it.
    """
    if isinstance(value, PrimaryPart):
        out = {"package": value.NAME, **_fields(value.values())}
        if value.extra:
            out["extra"] = value.extra.hex()
        if value.missing:
            out["missing"] = list(value.missing)
        return out
    if isinstance(value, RobotStateMessage):
        return {"package": value.NAME, "sub_packages": [as_json(s) for s in value.sub_packages]}
    if isinstance(value, BaseModel):
        fields = {k: getattr(value, k) for k in type(value).model_fields}
        return {"name": getattr(value, "NAME", type(value).__name__), **_fields(fields)}
    if isinstance(value, str):
        return value if value.isascii() else text_columns("", value)[""]
    if isinstance(value, (list, tuple)):
        return [as_json(v) for v in value]
    if isinstance(value, dict):
        return _fields(value)
    if isinstance(value, bytes):
        return value.hex()
    return value


def _fields(values: dict[str, Any]) -> dict[str, Any]:
    """Each value as_json; a text field adds `<name>_raw`, its bytes in hex when they are not
    UTF-8 (else ''), as capture tables do, so rows of one message keep one shape; a list of
    texts adds it only when one of them is not UTF-8."""
    out: dict[str, Any] = {}
    for name, value in values.items():
        if isinstance(value, str):
            out.update(text_columns(name, value))
            continue
        out[name] = as_json(value)
        if isinstance(value, (list, tuple)) and any(isinstance(v, str) and not v.isascii() for v in value):
            raws = [text_columns("", v)[RAW] if isinstance(v, str) else "" for v in value]
            if any(raws):
                out[name + RAW] = raws
    return out


def _lines(value: Any, indent: str) -> list[str]:
    out: list[str] = []
    enums: dict[str, str] = getattr(type(value), "ENUMS", {})
    items = (
        value.values()
        if isinstance(value, PrimaryPart)
        else {k: getattr(value, k) for k in type(value).model_fields}
    )
    for name, field_value in items.items():
        if isinstance(field_value, BaseModel):
            out.append(f"{indent}{name}:")
            out += _lines(field_value, indent + "  ")
        elif isinstance(field_value, (list, tuple)) and field_value and isinstance(field_value[0], BaseModel):
            for i, entry in enumerate(field_value):
                out.append(f"{indent}{name}[{i}]:")
                out += _lines(entry, indent + "  ")
        else:
            out.append(f"{indent}{name}: {describe(field_value, enums.get(name))}")
    if isinstance(value, PrimaryPart):
        missing, extra = ", ".join(value.missing), f"{len(value.extra)} bytes: {value.extra.hex()}"
        if value.missing and value.extra:  # neither older nor newer: another layout altogether
            out.append(f"{indent}(not this layout: missing {missing}; {extra} left over)")
        elif value.missing:
            out.append(f"{indent}(missing, older firmware: {missing})")
        elif value.extra:
            out.append(f"{indent}(extra {extra}, newer firmware)")
    return out


def safe_text_lines(lines: list[str]) -> str:
    """Lines joined for the terminal, wire text escaped line by line."""
    return "\n".join(safe_text(line) for line in lines)


def run_primary(
    chunks: Iterable[bytes],
    fmt: str,
    output: str | None,
    *,
    lenient: bool = False,
    left: Callable[[int | None], str] = lambda offset: "the rest of the input",
    version: str | None = None,
) -> int:
    """Decode a primary/secondary stream as it arrives; every message before an error is written first.

    With `lenient`, messages that do not decode are skipped and counted, and a
    stream that cannot be framed further ends the decode with a note, not an error.
    `left(offset)` says how much input there is from a framing fault on.
    """
    decoder = PrimaryStreamDecoder(skip_errors=lenient, version=version)
    writer: Writer | None = None
    received = 0
    error: RtdeSpecError | None = None
    try:
        for chunk in chunks:
            received += len(chunk)
            try:
                messages = decoder.feed(chunk)
            except RtdeSpecError as exc:
                error, messages = exc, decoder.decoded
            if fmt == "table":
                _print_tree(messages, decoder)
            elif messages:
                writer = writer or _open(fmt, output)
                _write(writer, messages, decoder)
            if error is not None:
                break
        else:
            try:
                decoder.close()
            except RtdeSpecError as exc:
                error = exc
    except BaseException as exc:
        if writer is not None:
            close_output(writer, exc, "message")
        raise
    fault = error if isinstance(error, DecodeError) and lenient else None
    if writer is not None:
        close_output(writer, error if fault is None else None, "message")
    if fmt == "table" and decoder.version is not None:
        source = "the version message" if decoder.announced else "--controller"
        print(f"controller version (from {source}): {decoder.version}")
    if not received:
        raise RtdeSpecError("no packages in the input")
    if lenient:
        report_skipped(decoder.skipped, fault, left(fault.offset if fault else None), "message")
    if error is not None and fault is None:
        raise error
    return 0


def _open(fmt: str, output: str | None) -> Writer:
    """json: one array of objects whatever the number of messages (its shape never varies)."""
    return open_writer(fmt, output)


def _write(writer: Writer, messages: list[tuple[int, Any]], decoder: PrimaryStreamDecoder) -> None:
    for offset, message in messages:
        warnings = _warnings(decoder, message)
        extra = {"warnings": warnings} if warnings else {}
        writer.write({"offset": offset, **as_json(message), **extra})


NO_VERSION = "no Version message in the input before it: --controller VERSION gives the robot's"


def _warnings(decoder: PrimaryStreamDecoder, message: Any) -> list[str]:
    """Why the message's values may be wrong; without a version, how to give one."""
    warnings = decoder.warnings_for(message)
    return [f"{w}; {NO_VERSION}" for w in warnings] if decoder.version is None else warnings


def _print_tree(messages: list[tuple[int, Any]], decoder: PrimaryStreamDecoder) -> None:
    for offset, message in messages:
        print(f"@{offset}  {message.NAME}")
        if isinstance(message, RobotStateMessage):
            for sub in message.sub_packages:
                print(f"  [{getattr(sub, 'NAME', 'unknown')}]")
                print(safe_text_lines(_lines(sub, "    ")))
        else:
            print(safe_text_lines(_lines(message, "  ")))
        for warning in _warnings(decoder, message):
            print(f"  warning: {warning}")
        print()
