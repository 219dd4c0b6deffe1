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


class _BoundedLoader(yaml.SafeLoader):
    """SafeLoader that refuses aliases and nesting deeper than MAX_DEPTH while composing."""

    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            event = self.peek_event()
            raise RefusedYamlError(
                None, None, f"YAML aliases (*{event.anchor}) are not allowed here", event.start_mark
            )
        if self._depth >= MAX_DEPTH:
            raise RefusedYamlError(
                None, None, f"YAML nests deeper than {MAX_DEPTH} levels", self.peek_event().start_mark
            )
        self._depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def load(text: str | bytes) -> Any:
    """The data of one YAML document, like `yaml.safe_load`, without aliases.

    A scalar Python refuses to convert (an integer of more than 4300 digits) is a
    YAMLError too, not a bare ValueError.
    """
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_data()
    except ValueError as exc:
        raise ConstructorError(None, None, f"value cannot be read: {exc}") from None
    finally:
        loader.dispose()


def compose(text: str | bytes) -> yaml.Node | None:
    """The node tree of one YAML document, like `yaml.compose(text, Loader=SafeLoader)`, without aliases."""
    loader = _BoundedLoader(text)
    try:
        return loader.get_single_node()  # type: ignore[no-any-return]
    finally:
        loader.dispose()
