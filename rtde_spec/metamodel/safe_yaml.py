"""YAML for files users hand us (recipes, scenarios, extra fields, the spec): no aliases, bounded depth.

`yaml.safe_load` builds no objects, but it still expands aliases: a 384-byte file of
nested aliases ("billion laughs") takes minutes and gigabytes. None of our files
needs an alias, so any alias is refused where it stands, before anything is
expanded; nesting deeper than MAX_DEPTH is refused too (instead of a RecursionError).
Every refusal is a `yaml.YAMLError` with a line and column, so callers that already
catch YAMLError need no change beyond calling `load` / `compose` from here.
"""

from __future__ import annotations

from typing import Any

import yaml
from yaml.composer import ComposerError
from yaml.constructor import ConstructorError

MAX_DEPTH = 100  # collections inside collections; our deepest file (the spec) uses ~10


class RefusedYamlError(ComposerError):
    """A YAML construct refused for safety (an alias, or too deep nesting)."""


#: libyaml where PyYAML has it: a file is parsed twice (events, then data) and still
#: takes a fifth of the pure-Python loader's time
_LOADER: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def check(text: str | bytes) -> None:
    """Raise RefusedYamlError at the first alias, or where nesting passes MAX_DEPTH.

    Walks the parser's events only: nothing is composed or expanded before the refusal.
    """
    depth = 0
    for event in yaml.parse(text, Loader=_LOADER):
        if isinstance(event, yaml.AliasEvent):
            raise RefusedYamlError(
                None, None, f"YAML aliases (*{event.anchor}) are not allowed here", event.start_mark
            )
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                raise RefusedYamlError(
                    None, None, f"YAML nests deeper than {MAX_DEPTH} levels", event.start_mark
                )
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1


def load(text: str | bytes) -> Any:
    """The data of one YAML document, like `yaml.safe_load`, without aliases.

    A scalar Python refuses to convert (an integer of more than 4300 digits) is a
    YAMLError too, not a bare ValueError.
    """
    check(text)
    try:
        return yaml.load(text, Loader=_LOADER)
    except ValueError as exc:
        raise ConstructorError(None, None, f"value cannot be read: {exc}") from None


def compose(text: str | bytes) -> yaml.Node | None:
    """The node tree of one YAML document, like `yaml.compose(text, Loader=SafeLoader)`, without aliases."""
    check(text)
    return yaml.compose(text, Loader=_LOADER)
