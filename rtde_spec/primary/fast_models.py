"""Build decoded models without re-validating what struct already typed.

A decoded Robot State has ~30 models; pydantic validation of values that come
straight from `struct` (ints in range by construction, exact tuple lengths)
costs most of the decode time. This fills the model's __dict__ the way
pydantic's own model_construct does, minus its per-field loop. The tests check
every decoded model equals its validated twin. Only for frozen models: the
fields-set record is shared between instances of a class.
"""

from __future__ import annotations

from typing import Any, TypeVar

from pydantic import BaseModel

M = TypeVar("M", bound=BaseModel)
_setattr = object.__setattr__
_PLANS: dict[type[BaseModel], tuple[int, dict[str, Any], set[str]]] = {}


def _plan(cls: type[BaseModel]) -> tuple[int, dict[str, Any], set[str]]:
    assert cls.model_config.get("frozen"), f"{cls.__name__} must be frozen"
    fields = cls.model_fields
    defaults = {n: i.default for n, i in fields.items() if not i.is_required()}
    plan = (len(fields), defaults, set(fields))
    _PLANS[cls] = plan
    return plan


def build(cls: type[M], values: dict[str, Any]) -> M:
    """An instance of `cls` holding `values` (plus defaults), unvalidated."""
    plan = _PLANS.get(cls) or _plan(cls)
    full = values if len(values) == plan[0] else {**plan[1], **values}
    obj = object.__new__(cls)
    _setattr(obj, "__dict__", full)
    _setattr(obj, "__pydantic_fields_set__", plan[2])
    _setattr(obj, "__pydantic_extra__", None)
    _setattr(obj, "__pydantic_private__", None)
    return obj
