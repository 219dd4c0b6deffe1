"""The tables of built-in functions: each builtins module enters its functions in its own table
with the decorator `registrar` makes, and `builtins.py` merges the tables."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])


def registrar(table: dict[str, Any]) -> Callable[..., Callable[[F], F]]:
    """A decorator that enters a function in `table` under each name given: each builtins module
    fills its own table this way, and `builtins.py` merges them."""

    def names(*given: str) -> Callable[[F], F]:
        def register(fn: F) -> F:
            for name in given:
                table[name] = fn
            return fn

        return register

    return names
