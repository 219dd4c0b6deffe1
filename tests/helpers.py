"""Helpers shared by the tests: the golden vectors and one check for every package."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from rtde_spec._generated import rtde_models as gen
from rtde_spec._generated import rtde_structs
from rtde_spec.rtde.codec import decode, encode, message_by_name
from rtde_spec.wire.rtde_layouts import layouts
from rtde_spec.wire.rtde_messages import RtdeMessage

DATA = Path(__file__).parent / "data"
ROOT = Path(__file__).resolve().parent.parent


def golden() -> list[dict[str, Any]]:
    return yaml.safe_load((DATA / "rtde_golden.yaml").read_text())


def expected_values(package: str, fields: dict[str, Any]) -> dict[str, Any]:
    """Golden field values as the model holds them (bytes fields are hex in YAML)."""
    cls = message_by_name(package)
    out = {}
    for fld in layouts()[cls.NAME].fields:
        value = fields[fld.name]
        out[fld.name] = bytes.fromhex(value) if fld.kind == "bytes" else value
    return out


def assert_package(data: bytes, message: RtdeMessage, sender: str, protocol: int) -> None:
    """decode, encode and size agree for one package: the construct-tests idiom.

    Checks the codec both ways, the generated body struct (parse, build, and
    sizeof where the layout is fixed) and the generated whole-package struct.
    """
    cls = type(message)
    assert decode(data, sender=sender, protocol_version=protocol) == message  # type: ignore[arg-type]
    assert encode(message) == data
    body = data[gen.HEADER_SIZE :]
    values = message.fields()
    assert cls.STRUCT.build(values) == body
    parsed = cls.STRUCT.parse(body)
    assert {k: parsed[k] for k in values} == values
    if layouts()[cls.NAME].fixed_size is not None:
        assert cls.STRUCT.sizeof() == len(body)
    whole = getattr(rtde_structs, f"{cls.NAME.upper()}_PACKAGE")
    assert whole.build({"body": values}) == data
    assert whole.parse(data).size == len(data)
