"""The Script Directory's text functions a program takes a text apart with: str_at, str_empty,
str_find and str_sub (module internals; str_len, str_cat, to_str and to_num are in builtins.py).

Positions count from 0. The manual counts bytes; these count characters, the same for the ASCII
texts programs exchange with their sockets and devices.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rtde_spec.emulator.urscript.calls import INT_MAX, arg, type_name
from rtde_spec.emulator.urscript.interfaces import Runner
from rtde_spec.emulator.urscript.nodes import ScriptFault, Stmt
from rtde_spec.emulator.urscript.registry import registrar

Args = list[Any]
Kwargs = dict[str, Any]
TEXT: dict[str, Callable[[Runner, Stmt, Args, Kwargs], Any]] = {}
_builtin = registrar(TEXT)


def _text(stmt: Stmt, value: Any, name: str) -> str:
    if not isinstance(value, str):
        raise ScriptFault(f"{stmt.name}: {name} must be a string, not {type_name(value)}", stmt.line, 1)
    return value


def _position(stmt: Stmt, value: Any, name: str, top: int) -> int:
    """An int from 0 to `top`, else the runtime exception the manual names (out of bounds)."""
    if type(value) is not int or not 0 <= value <= top:
        raise ScriptFault(f"{stmt.name}: {name} {value!r} is out of bounds (0 to {top})", stmt.line, 1)
    return value


@_builtin("str_at")
def _str_at(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> str:
    """The character at `index`: str_at("Hello", 1) is "e"; past the end, or of "", an error."""
    src = _text(stmt, arg(stmt, args, kwargs, 0, "src"), "src")
    if not src:
        raise ScriptFault(f"{stmt.name}: the source string is empty", stmt.line, 1)
    return src[_position(stmt, arg(stmt, args, kwargs, 1, "index"), "index", len(src) - 1)]


@_builtin("str_empty")
def _str_empty(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> bool:
    return not _text(stmt, arg(stmt, args, kwargs, 0, "str"), "str")


@_builtin("str_find")
def _str_find(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> int:
    """Where `target` first is in `src` from `start_from`, -1 if nowhere: str_find("Hello World!",
    "o", 5) is 7."""
    src = _text(stmt, arg(stmt, args, kwargs, 0, "src"), "src")
    target = _text(stmt, arg(stmt, args, kwargs, 1, "target"), "target")
    start = _position(stmt, arg(stmt, args, kwargs, 2, "start_from", 0), "start_from", INT_MAX)
    return src.find(target, start)


@_builtin("str_sub")
def _str_sub(runner: Runner, stmt: Stmt, args: Args, kwargs: Kwargs) -> str:
    """At most `len` characters from `index` (to the end without `len`): str_sub("abcde", 2, 50)
    is "cde"; an index past the end or a negative one is an error."""
    src = _text(stmt, arg(stmt, args, kwargs, 0, "src"), "src")
    index = _position(stmt, arg(stmt, args, kwargs, 1, "index"), "index", len(src))
    size = _position(stmt, arg(stmt, args, kwargs, 2, "len", INT_MAX), "len", INT_MAX)
    return src[index : index + size]
