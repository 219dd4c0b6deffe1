"""Recipe files in XML: UR's `<recipe key=...>` and URBasic's `<receive>`/`<send>`.

UR's client library names each recipe `<recipe key="out">`; the direction follows from the
names. URBasic (Rope Robotics' client, copied into many robot projects) reads its own
`rtdeConfiguration.xml`: the outputs under `<receive key="out">`, the inputs under
`<send key="in">` (its fields carry an `initValue` it sends first, not part of the recipe),
so there the element names the direction. Parsed with defusedxml: no entity expansion,
no external entities or DTDs.
"""

from __future__ import annotations

import re
from xml.etree.ElementTree import Element

import defusedxml.ElementTree as SafeET
from defusedxml import DefusedXmlException

from rtde_spec.errors import RecipeError
from rtde_spec.recipes.model import Direction, Recipe

_XML_DECLARATION = re.compile(r"^\s*<\?xml[^>]*\?>")
# element -> the direction its fields have (None: told by the names)
RECIPE_ELEMENTS: dict[str, Direction | None] = {"recipe": None, "receive": "output", "send": "input"}


def from_xml(text: str, where: str) -> list[Recipe]:
    """Every recipe of an `<rtde_config>` document, in document order."""
    subject = f"file {where}"
    try:  # the text is decoded already: a declaration naming its encoding would be refused
        root = SafeET.fromstring(_XML_DECLARATION.sub("", text, count=1), forbid_dtd=True)
    except DefusedXmlException as exc:
        raise RecipeError(f"unsafe XML refused: {exc}", subject=subject) from None
    except SafeET.ParseError as exc:
        line, col = exc.position
        raise RecipeError(f"not well-formed XML at line {line}, column {col}", subject=subject) from None
    if root.tag != "rtde_config":
        raise RecipeError("XML root must be <rtde_config>", subject=subject, actual=f"<{root.tag}>")
    recipes = [
        _recipe(element, number, subject)
        for number, element in enumerate((e for e in root if e.tag in RECIPE_ELEMENTS), 1)
    ]
    if not recipes:
        raise RecipeError(
            "no <recipe> elements (nor URBasic's <receive>/<send>)",
            subject=subject,
            actual=", ".join(sorted({f"<{e.tag}>" for e in root if isinstance(e.tag, str)})) or "nothing",
        )
    return recipes


def _recipe(element: Element, number: int, subject: str) -> Recipe:
    key = element.get("key")
    names: list[str] = []
    declared: dict[str, str] = {}
    for fld in element.findall("field"):
        name = (fld.get("name") or "").strip()  # XML turns a line break in a value into a space
        if not name:
            raise RecipeError(f"<field> without a name in recipe {key or number}", subject=subject)
        names.append(name)
        if fld.get("type"):
            declared[name] = fld.get("type", "")
    return Recipe(tuple(names), key=key, declared_types=declared, direction=RECIPE_ELEMENTS[element.tag])
