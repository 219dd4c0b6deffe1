"""Turn pydantic's ValidationError into EncodeError naming the package, field and limit."""

from __future__ import annotations

from pydantic import ValidationError

from .errors import EncodeError


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


def encode_error(exc: ValidationError, package: str) -> EncodeError:
    """The first problem as the headline; every other one listed in the reason."""
    errors = exc.errors(include_url=False)
    first = errors[0]
    field = ".".join(str(p) for p in first["loc"]) or None
    reason = str(first["msg"])
    ctx = first.get("ctx") or {}
    expected = _expected(ctx)
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
