"""Build decoded models without re-validating what struct already typed.

A decoded Robot State has ~30 models; pydantic validation of values that come
straight from `struct` (ints in range by construction, exact tuple lengths)
costs most of the decode time. This fills the model's __dict__ the way
pydantic's own model_construct does, minus its per-field loop, and leaves
pydantic's three bookkeeping slots (fields set, extra, private) unset:
`PrimaryModel.__getattr__` answers for them, so each model costs one allocation
and one dict. The tests check every decoded model equals its validated twin and
survives copy, pickle and dumps. Only for frozen PrimaryModels.

The models defer their schemas (`defer_build`) until first validated, which a decoded
model never is: `complete` builds a class's schema when code that makes it unvalidated
is set up (a maker here, a generated decoder in compiled.py), so pydantic-core finds a
real serializer wherever it serializes one (`to_json`, a TypeAdapter, a parent model).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from pydantic import BaseModel

from rtde_spec._generated import primary_models as gen
from rtde_spec.wire.layout import Layout
from rtde_spec.wire.primary_base import PrimaryModel

M = TypeVar("M", bound=PrimaryModel)
_set_dict = BaseModel.__dict__["__dict__"].__set__
_new = object.__new__
_MAKERS: dict[type[PrimaryModel], Callable[[dict[str, Any]], Any]] = {}


def complete(cls: type[BaseModel]) -> None:
    """Build `cls`'s deferred schema (validator and serializer), once."""
    if not cls.__pydantic_complete__:
        cls.model_rebuild()


def maker(cls: type[M]) -> Callable[[dict[str, Any]], M]:
    """A function that builds `cls` from a dict of its values, unvalidated (made once per class)."""
    found = _MAKERS.get(cls)
    if found is not None:
        return found
    assert cls.model_config.get("frozen"), f"{cls.__name__} must be frozen"
    complete(cls)
    fields = cls.model_fields
    count = len(fields)
    defaults = {n: i.default for n, i in fields.items() if not i.is_required()}

    def make(values: dict[str, Any]) -> M:
        obj = _new(cls)
        _set_dict(obj, values if len(values) == count else {**defaults, **values})
        return obj  # type: ignore[no-any-return]

    _MAKERS[cls] = make
    return make


def build(cls: type[M], values: dict[str, Any]) -> M:
    """An instance of `cls` holding `values` (plus defaults), unvalidated."""
    return maker(cls)(values)


def with_groups(layout: Layout, values: dict[str, Any]) -> dict[str, Any]:
    """Nested group dicts of a decoded part turned into their generated models."""
    for fld in layout.group_fields:
        if values.get(fld.name) is None:
            continue
        inner = layout.groups[fld.name]
        cls = gen.GROUPS[fld.group or ""]
        value = values[fld.name]
        make = maker(cls)
        if fld.kind == "optional":
            values[fld.name] = make(with_groups(inner, value))
        elif inner.group_fields:
            entries = [make(with_groups(inner, v)) for v in value]
            values[fld.name] = tuple(entries) if isinstance(fld.repeat, int) else entries
        else:
            entries = [make(v) for v in value]
            values[fld.name] = tuple(entries) if isinstance(fld.repeat, int) else entries
    return values
