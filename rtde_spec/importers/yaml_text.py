"""The YAML round trip `spec import --write` edits spec files with (ruamel.yaml: comments, order
and quotes kept), writing text the spec's own loader (PyYAML, YAML 1.1) reads back the same."""

from __future__ import annotations

import io
import re
from typing import Any

# plain words YAML 1.1 reads as a bool or null, which ruamel (YAML 1.2) writes unquoted: a
# description that is only "yes" was written so and read back as True (then refused)
_WORDS = "yes|no|on|off|true|false|null"
_NOT_TEXT_IN_1_1 = re.compile("|".join(f"{w}|{w.capitalize()}|{w.upper()}" for w in _WORDS.split("|")) + "|~")


def round_trip() -> Any:
    """A ruamel YAML that edits a spec file in place, as it is laid out."""
    from ruamel.yaml import YAML
    from ruamel.yaml.representer import RoundTripRepresenter

    class Representer(RoundTripRepresenter):
        pass

    def text(representer: Any, data: str) -> Any:
        if _NOT_TEXT_IN_1_1.fullmatch(data):
            return representer.represent_scalar("tag:yaml.org,2002:str", data, style='"')
        return RoundTripRepresenter.represent_str(representer, data)

    Representer.add_representer(str, text)
    yaml = YAML(typ="rt")
    yaml.Representer = Representer
    yaml.preserve_quotes = True
    yaml.width = 4096
    yaml.indent(mapping=2, sequence=4, offset=2)
    return yaml


def flow(data: dict[str, Any] | list[Any]) -> Any:
    """`data` written on one line (`[a, b]`, `{cb3: 3.4.0}`), as the spec writes such values."""
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    node: Any = CommentedMap(data) if isinstance(data, dict) else CommentedSeq(data)
    node.fa.set_flow_style()
    return node


def dump(yaml: Any, data: Any) -> str:
    buf = io.StringIO()
    yaml.dump(data, buf)
    return buf.getvalue()
