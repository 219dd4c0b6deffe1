"""The readable construct definition of a recipe's data package (for users parsing with construct).

Kept apart from the codec: construct is imported only when someone asks for it, and
the codec's own methods are the fast path.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from rtde_spec._generated.constants import DATA_PACKAGE_PREFIX_FIELDS, DATA_PACKAGE_TYPE
from rtde_spec.recipes.encoding import PREFIX, RecipeItem


def recipe_construct(items: Sequence[RecipeItem], package_size: int) -> Any:
    """A construct Struct of a whole data package (header, recipe id, fields); building fills in the size."""
    from construct import Array, Const, FormatField, Rebuild, Struct

    def field(code: str) -> Any:
        # construct names the standard 4-byte ints "l"/"L" where struct also takes "i"/"I"
        return FormatField(PREFIX.format[0], {"i": "l", "I": "L"}.get(code, code))

    size_c, type_c, id_c = (field(code) for code in PREFIX.format[1:])
    fields = []
    for item in items:
        one = field(item.wire.struct[-1])
        fields.append(item.name / (one if item.wire.count == 1 else Array(item.wire.count, one)))
    return Struct(
        DATA_PACKAGE_PREFIX_FIELDS[0] / Rebuild(size_c, lambda _: package_size),
        DATA_PACKAGE_PREFIX_FIELDS[1] / Const(DATA_PACKAGE_TYPE, type_c),
        DATA_PACKAGE_PREFIX_FIELDS[2] / id_c,
        *fields,
    )
