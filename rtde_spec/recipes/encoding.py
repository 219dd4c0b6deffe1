"""Encoding data packages: one `struct` call on the happy path, a detailed check to explain a failure.

`struct` already refuses integers out of range and non-numbers, so a valid input
costs one generated flatten and one pack. What `struct` would let through (a
vector that is not a list or tuple, or of the wrong length, a BOOL that is not
0/1) is checked inline; strict mode adds one C-level type check per wire kind
(`{float, int}` for doubles, `{int}` for integers, `{bool}` for BOOL) over the
flat tuple. Anything that fails goes through the per-value checks, which either
convert it (an integral float for an integer, a numpy scalar or 1-D array, an
IntEnum) or raise EncodeError naming the field, the limit and the value. A dict,
set, string or bytes is never a vector: unpacking one would send its keys, an
arbitrary order or character codes. NaN and infinities are valid doubles: the
spec sets no range for DOUBLE fields and the controller takes IEEE 754 values.
"""

from __future__ import annotations

import dataclasses
import math
import operator
import struct
import sys
from collections.abc import Mapping, Sequence, Set
from dataclasses import dataclass
from operator import itemgetter
from typing import Any

from rtde_spec._generated.constants import BYTE_ORDER, DATA_PACKAGE_PREFIX_FORMAT, DATA_PACKAGE_TYPE
from rtde_spec.errors import DecodeError, EncodeError
from rtde_spec.metamodel.catalogue import FieldInfo, WireTypeInfo

PREFIX = struct.Struct(DATA_PACKAGE_PREFIX_FORMAT)


@dataclass(frozen=True)
class RecipeItem:
    """One variable of a recipe: its name, wire type, and byte offset in the payload."""

    name: str
    wire: WireTypeInfo
    offset: int
    info: FieldInfo | None = None


class _Refused(Exception):
    """The fast path saw something struct would accept but the recipe does not."""


def _is_bool(value: Any) -> bool:
    return value is True or value is False or (type(value) is int and value in (0, 1))


_STRICT_TYPES = {
    "float": frozenset({float, int}),
    "int": frozenset({int}),
    "bool": frozenset({bool}),
}
"""The exact Python types strict mode takes per wire kind without a closer look."""
_CANONICAL = {"float": float, "int": int, "bool": bool}
"""The type a value of each wire kind usually has (what decoding gives)."""

_FAST_ERRORS = (KeyError, TypeError, struct.error, OverflowError, _Refused)
"""What the one-call path may raise; every one is explained (or converted) by `checked`."""


def _strict_checks(
    items: Sequence[RecipeItem], names: Sequence[str], scope: dict[str, Any], leading: int, pad: str
) -> list[str]:
    """Source lines refusing the values unless each has a type strict mode takes for its kind.

    First the usual case, every value of its kind's own type: with no vectors each
    type compared inline (no call); with vectors every value's type in one C loop
    over `t`, the packed arguments (`leading` ints, then the values: cheaper than ~40
    inline checks and a second tuple).
    Only if that fails, one `set(map(type, ...)) <= allowed` per kind (ints pass
    for doubles). Strict costs a few calls per package, not one per value.
    """
    vectors = [x for x, item in zip(names, items, strict=True) if item.wire.count > 1]
    lines = []
    if vectors:  # their own types were checked with their lengths
        kinds = [_CANONICAL[i.wire.kind] for i in items for _ in range(i.wire.count)]
        scope["canon"] = [int] * leading + kinds
        lines.append(f"{pad}if [*map(type, t)] != canon:")
    else:  # float, int, bool: the builtins' names in the code
        pairs = zip(names, items, strict=True)
        inline = " and ".join(f"type({x}) is {_CANONICAL[i.wire.kind].__name__}" for x, i in pairs)
        lines.append(f"{pad}if not ({inline}):")
    groups: dict[str, list[str]] = {}
    for x, item in zip(names, items, strict=True):
        groups.setdefault(item.wire.kind, []).append(x if item.wire.count == 1 else f"*{x}")
    for k, (kind, parts) in enumerate(sorted(groups.items())):
        scope[f"ok{k}"] = _STRICT_TYPES[kind]
        lines.append(f"{pad}    if not set(map(type, ({', '.join(parts)},))) <= ok{k}: raise Refused")
    return lines


def _compile_encode(
    items: Sequence[RecipeItem], packer: struct.Struct, lead: str, slow: Any, params: str = ""
) -> Any:
    """One function from a dict of values to packed bytes, written once per recipe, both modes.

    `lead` is what is packed before the values ("" for a payload), `params` the arguments
    it names after `values` (constants such as the package size are written into the
    code); its last parameter is `strict`, as the public method's. A dict of the
    recipe's size goes through one `struct` call; anything the generated checks refuse
    (`_Refused`, or KeyError, TypeError, struct.error) and anything not such a dict
    goes to `slow` with the same arguments, which converts or explains it. One Python
    frame per call: the method a user calls is this function. strict: every value has
    a type strict mode takes for its kind; otherwise BOOL values are bools or 0/1.
    Ranges are struct's to check.
    """
    scope: dict[str, Any] = {
        "Refused": _Refused,
        "is_bool": _is_bool,
        "pack": packer.pack,
        "slow": slow,
        "ERRORS": _FAST_ERRORS,
    }
    names = [f"x{i}" for i in range(len(items))]
    args = f"values{', ' + params if params else ''}"
    lines = [
        f"def encode({args}, strict=False):",
        f"    if type(values) is dict and len(values) == {len(items)}:",
        "        try:",
    ]
    pad = " " * 12
    if len(items) == 1:
        lines.append(f"{pad}x0 = values[{items[0].name!r}]")
    else:  # every value in one C call; a missing name raises KeyError
        scope["get"] = itemgetter(*(item.name for item in items))
        lines.append(f"{pad}{', '.join(names)} = get(values)")
    vectors = [x for x, item in zip(names, items, strict=True) if item.wire.count > 1]
    if vectors:  # lists or tuples (a dict, set or str would unpack), each of its length
        counts = [item.wire.count for item in items if item.wire.count > 1]
        inline = " and ".join(  # type() and len() inline are specialised: cheaper than any C loop over them
            f"(type({x}) is tuple or type({x}) is list) and len({x}) == {n}"
            for x, n in zip(vectors, counts, strict=True)
        )
        lines.append(f"{pad}if not ({inline}): raise Refused")
    parts = [x if item.wire.count == 1 else f"*{x}" for x, item in zip(names, items, strict=True)]
    values = ", ".join(([lead] if lead else []) + parts)
    lines.append(f"{pad}if not strict:")
    for x, item in zip(names, items, strict=True):
        if item.wire.kind == "bool":
            check = f"is_bool({x})" if item.wire.count == 1 else f"all(map(is_bool, {x}))"
            lines.append(f"{pad}    if not {check}: raise Refused")
    lines.append(f"{pad}    return pack({values})")
    if vectors:  # the arguments in `t`: checked, then packed
        lines.append(f"{pad}t = ({values},)")
        values = "*t"
    lines.extend(_strict_checks(items, names, scope, lead.count(",") + 1 if lead else 0, pad))
    lines.append(f"{pad}return pack({values})")
    lines.append("        except ERRORS:")
    lines.append("            pass  # explained (or converted) by the checks")
    lines.append(f"    return slow({args}, strict)")
    exec("\n".join(lines), scope)
    return scope["encode"]


def install(obj: Any, base: type, **generated: Any) -> None:
    """Each generated function as `obj`'s method of its name, under that method's name and
    docstring (for help()); not where `obj`'s class overrides `base`'s method (a subclass's own
    would otherwise never run)."""
    for name, function in generated.items():
        method = getattr(base, name)
        if getattr(type(obj), name) is not method:
            continue
        for attr in ("__name__", "__qualname__", "__doc__", "__module__"):
            setattr(function, attr, getattr(method, attr))
        setattr(obj, name, function)


class Encoder:
    """Encodes one recipe's values into a payload or a whole data package."""

    def __init__(self, items: Sequence[RecipeItem], payload: struct.Struct, package_size: int) -> None:
        self.items = tuple(items)
        self.names = frozenset(i.name for i in items)
        self.payload_struct = payload
        self.package_struct = struct.Struct(PREFIX.format + payload.format[1:])
        self.package_size = package_size
        self.encode = _compile_encode(items, payload, "", self._explained_payload)
        """encode(values, strict=False): the payload; one `struct` call for a dict of builtins."""
        lead = f"{package_size}, {DATA_PACKAGE_TYPE}, recipe_id"  # the prefix's constants written in
        self.encode_package = _compile_encode(
            items, self.package_struct, lead, self._explained_package, "recipe_id"
        )
        """encode_package(values, recipe_id, strict=False): a whole data package, as `encode`."""

    def _explained_payload(self, values: Any, strict: bool) -> bytes:
        """What the one-call path refused: converted value by value, or EncodeError."""
        return self.payload_struct.pack(*self.checked(values, strict))

    def _explained_package(self, values: Any, recipe_id: int, strict: bool) -> bytes:
        try:
            PREFIX.pack(self.package_size, DATA_PACKAGE_TYPE, recipe_id)
        except (struct.error, TypeError):
            low, high = _bounds(PREFIX.format[-1])
            raise EncodeError(
                "recipe id out of range",
                package="data_package",
                field="recipe_id",
                expected=f"{low}..{high}",
                actual=recipe_id,
            ) from None
        flat = self.checked(values, strict)
        return self.package_struct.pack(self.package_size, DATA_PACKAGE_TYPE, recipe_id, *flat)

    def checked(self, values: Any, strict: bool) -> list[Any]:
        """Every value checked against its wire type; the first problem raises, naming the field."""
        values = as_mapping(values)
        flat: list[Any] = []
        for item in self.items:
            if item.name not in values:
                raise EncodeError("missing value", package="data_package", field=item.name)
            value = values[item.name]
            if item.wire.count > 1:
                problem = _not_a_vector(value, item.wire.count)
                if problem is not None:
                    raise EncodeError(
                        f"{item.wire.name} needs exactly {item.wire.count} values in order: {problem}",
                        package="data_package",
                        field=item.name,
                        expected=f"{item.wire.count} values",
                        actual=repr(value),
                    )
                flat.extend(_checked(item, v, strict, i) for i, v in enumerate(value))
            else:
                flat.append(_checked(item, value, strict, None))
        extra = set(values) - self.names
        if extra:
            raise EncodeError(
                f"not in the recipe: {', '.join(sorted(extra))}",
                package="data_package",
                field=sorted(extra)[0],
            )
        return flat


def as_mapping(values: Any) -> Mapping[str, Any]:
    """Values by name from a dict, a record (a namedtuple), a pydantic model, a dataclass or
    anything with `keys()` (a pandas row); EncodeError for anything else."""
    if isinstance(values, Mapping):
        return values
    if hasattr(values, "model_dump"):  # a pydantic model (pydantic is imported only when used)
        return values.model_dump()  # type: ignore[no-any-return]
    if isinstance(values, tuple):
        if not hasattr(values, "_asdict"):
            raise EncodeError(
                "a plain tuple has no field names; pass a record, dict or model", package="data_package"
            )
        return values._asdict()  # type: ignore[no-any-return]
    if dataclasses.is_dataclass(values) and not isinstance(values, type):
        return {f.name: getattr(values, f.name) for f in dataclasses.fields(values)}
    if callable(getattr(values, "keys", None)) and hasattr(values, "__getitem__"):
        return {key: values[key] for key in values.keys()}
    raise EncodeError(
        f"values must be a dict, a record, a model or a dataclass, not {type(values).__name__}",
        package="data_package",
    )


def expected_recipe_id(recipe_id: Any) -> int:
    """The recipe id a decoder is told to look for, or DecodeError when no package can carry it
    (a text, a float, one outside the prefix's integer): never a bare struct.error."""
    low, high = _bounds(PREFIX.format[-1])
    number = _index_or_none(recipe_id)
    if number is None or not low <= number <= high:
        raise DecodeError(
            "no data package carries this recipe id",
            package="data_package",
            field="recipe_id",
            expected=f"an integer {low}..{high}",
            actual=repr(recipe_id),
        )
    return number


def _bounds(code: str) -> tuple[int, int]:
    bits = 8 * struct.calcsize(BYTE_ORDER + code)
    return (0, (1 << bits) - 1) if code.isupper() else (-(1 << (bits - 1)), (1 << (bits - 1)) - 1)


def _not_a_vector(value: Any, count: int) -> str | None:
    """Why `value` is not `count` values in order (None when it is): what unpacking would get wrong.

    Lists, tuples, 1-D numpy arrays, `array.array`, ranges and other sequences are
    vectors; a mapping would send its keys, a set its values in no set order, a
    string or bytes its character codes."""
    if isinstance(value, (str, bytes, bytearray, memoryview)):
        return "text or bytes, not numbers"
    if isinstance(value, Mapping):
        return "a mapping would send its keys"
    if isinstance(value, Set):
        return "a set has no order"
    ndim = getattr(value, "ndim", 1)
    if ndim != 1:
        return f"an array of {ndim} dimensions, not 1"
    if not (isinstance(value, Sequence) or hasattr(value, "__array__")):
        return f"a {type(value).__name__}, not a list, tuple or 1-D array"
    if len(value) != count:
        return f"{len(value)} given"
    return None


def _index_or_none(value: Any) -> int | None:
    """The integer `value` stands for (`__index__`, as struct takes it), or None."""
    try:
        return operator.index(value)
    except TypeError:
        return None


def _is_numpy_bool(value: Any) -> bool:
    kind = getattr(getattr(value, "dtype", None), "kind", None)
    return kind == "b" and getattr(value, "ndim", None) == 0


def _checked(item: RecipeItem, value: Any, strict: bool, at: int | None) -> Any:
    """One value as the wire type takes it, or EncodeError.

    Without strict, a value is taken as `struct` takes it (anything with `__index__`
    for an integer, with `__float__` or `__index__` for a double: numpy scalars,
    Fraction, Decimal), so the one-call path and these checks agree; integral
    floats become integers and 0/1 (numpy bools too) BOOLs."""
    wire = item.wire
    field = item.name if at is None else f"{item.name}[{at}]"

    def fail(reason: str, expected: Any) -> EncodeError:
        return EncodeError(reason, package="data_package", field=field, expected=expected, actual=repr(value))

    kind = type(value)
    text = issubclass(kind, (str, bytes, bytearray))
    if wire.kind == "bool":
        if isinstance(value, bool):
            return value
        if not strict and not text:
            if _is_numpy_bool(value):
                return bool(value)
            index = _index_or_none(value)
            if index in (0, 1):
                return bool(index)
        raise fail("not a bool", "True or False" if strict else "a bool, 0 or 1")
    if strict:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            what = "an integer" if wire.kind == "int" else "a number"
            if (
                not isinstance(value, bool)
                and not text
                and hasattr(kind, "__index__" if wire.kind == "int" else "__float__")
            ):
                # a numpy int32 *is* an integer: say what strict mode refuses in it, its type
                py = "int" if wire.kind == "int" else "int or float"
                raise fail(
                    f"strict mode takes a Python {py} for {wire.name}, not {kind.__module__}.{kind.__name__}",
                    wire.name,
                )
            raise fail(f"not {what} for {wire.name}", wire.name)
    elif text or not (hasattr(kind, "__index__") or hasattr(kind, "__float__")):
        what = "an integer" if wire.kind == "int" else "a number"
        raise fail(f"not {what} for {wire.name}", wire.name)
    if wire.kind == "int":
        if hasattr(kind, "__index__"):
            try:
                value = operator.index(value)
            except TypeError:  # a numpy array of one value has __index__ but refuses it
                raise fail(f"not an integer for {wire.name}", wire.name) from None
        else:
            try:
                number = float(value)
            except (TypeError, ValueError, OverflowError):
                number = math.nan
            if strict or not number.is_integer():
                raise fail(f"not an integer for {wire.name}", wire.name)
            value = int(number)
        assert wire.bounds is not None
        low, high = wire.bounds
        if not low <= value <= high:
            raise fail(f"out of range for {wire.name}", f"{low}..{high}")
        return value
    try:
        return float(value)
    except OverflowError:  # an int beyond the largest double
        raise fail(f"out of range for {wire.name}", f"|value| <= {sys.float_info.max!r}") from None
    except (TypeError, ValueError):  # its __float__ refused
        raise fail(f"not a number for {wire.name}", wire.name) from None
