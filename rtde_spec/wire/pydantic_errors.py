"""Turn pydantic's ValidationError into EncodeError naming the package, field and limit."""

from __future__ import annotations

from typing import Any, get_args

from pydantic import BaseModel, ValidationError

from rtde_spec.errors import EncodeError

_BOUND_WORDS = {"ge": ">=", "gt": ">", "le": "<=", "lt": "<"}


def _expected(ctx: dict[str, object]) -> str | None:
    if "ge" in ctx and "le" in ctx:
        return f"{ctx['ge']}..{ctx['le']}"
    parts = [f"{_BOUND_WORDS[k]} {v}" for k, v in ctx.items() if k in _BOUND_WORDS]
    if "max_length" in ctx:
        parts.append(f"at most {ctx['max_length']} items/characters")
    if "expected" in ctx:
        parts.append(str(ctx["expected"]))
    return ", ".join(parts) or None


def _bounds_in(annotation: Any, metadata: list[Any]) -> tuple[Any, Any]:
    """ge/le from a field's metadata or anywhere inside its annotation (Optional, Annotated)."""
    low = high = None
    stack: list[Any] = [annotation, *metadata]
    while stack:
        item = stack.pop()
        low = getattr(item, "ge", low) if getattr(item, "ge", None) is not None else low
        high = getattr(item, "le", high) if getattr(item, "le", None) is not None else high
        stack.extend(getattr(item, "metadata", []) or [])
        stack.extend(get_args(item))
    return low, high


def _declared_bounds(model: type[BaseModel] | None, field: str | None) -> str | None:
    """'0..255' from the field's own ge/le, however nested its Annotated metadata is."""
    if model is None or field not in model.model_fields:
        return None
    info = model.model_fields[field]
    low, high = _bounds_in(info.annotation, list(info.metadata))
    return f"{low}..{high}" if low is not None and high is not None else None


def encode_error(exc: ValidationError, package: str, model: type[BaseModel] | None = None) -> EncodeError:
    """The first problem as the headline; every other one listed in the reason."""
    errors = exc.errors(include_url=False)
    first = errors[0]
    field = ".".join(str(p) for p in first["loc"]) or None
    reason = str(first["msg"])
    ctx = first.get("ctx") or {}
    expected = _declared_bounds(model, field) or _expected(ctx)
    if len(errors) > 1:
        rest = "; ".join(f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in errors[1:])
        reason += f" (and {len(errors) - 1} more: {rest})"
    actual = first.get("input") if first["type"] != "missing" else None
    return EncodeError(
        reason,
        package=package,
        field=field,
        expected=expected or None,
        actual=repr(actual) if actual is not None else None,
    )
