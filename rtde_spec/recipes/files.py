"""Recipe files: UR's XML configuration, one name per line, comma lists, YAML and JSON.

XML is parsed with defusedxml (no entity expansion, no external entities or DTDs),
YAML without aliases (no "billion laughs") and bounded nesting, JSON with its
nesting bounded by the interpreter's recursion limit (an error, not a crash);
every file is size-bounded before it is parsed.
"""

from __future__ import annotations

import codecs
import json
import re
from pathlib import Path
from typing import Any
from xml.etree.ElementTree import Element, SubElement, tostring

import yaml

from rtde_spec.errors import RecipeError, UsageError
from rtde_spec.metamodel import safe_yaml
from rtde_spec.recipes.model import FILE_FORMATS, Direction, Recipe, check_savable
from rtde_spec.recipes.xml_recipes import from_xml

MAX_FILE_BYTES = 1 << 20  # 1 MiB: recipes are names; anything larger is not a recipe
FORMATS = FILE_FORMATS


def at(where: str) -> str:
    """How an error names the recipe file it is about."""
    return f"file {where}"


def detect_format(path: Path, text: str) -> str:
    """By extension first, then by content."""
    suffix = path.suffix.lower()
    by_suffix = {".xml": "xml", ".yaml": "yaml", ".yml": "yaml", ".json": "json", ".csv": "csv"}
    if suffix in by_suffix:
        return by_suffix[suffix]
    stripped = text.lstrip()
    if stripped.startswith("<"):
        return "xml"
    if stripped.startswith(("{", "[")):
        return "json"
    if any(line.strip().startswith(("recipes:", "fields:", "- ")) for line in text.splitlines()):
        return "yaml"
    first = next((line for line in _uncommented(text) if line), "")
    return "csv" if "," in first or ";" in first else "lines"


def _uncommented(text: str) -> list[str]:
    """Lines without `#` comments (whole-line and trailing), stripped."""
    return [line.split("#", 1)[0].strip() for line in text.splitlines()]


def read_text_bounded(path: Path) -> str:
    """The file's text, refused before reading when it is too large or no regular file (a pipe
    would wait for a writer, a device has no size to bound it by)."""
    from rtde_spec.output.partfile import kind_of

    try:
        size = path.stat().st_size
    except OSError as exc:
        raise RecipeError(f"cannot read recipe file: {exc.strerror}", subject=f"file {path}") from None
    kind = kind_of(path)
    if kind is not None:
        raise RecipeError(
            f"is {kind}, not a recipe file; give a regular file (UR's XML, YAML, JSON, or one name per line)",
            subject=f"file {path}",
        )
    if size > MAX_FILE_BYTES:
        raise RecipeError(
            "recipe file too large",
            subject=f"file {path}",
            expected=f"<= {MAX_FILE_BYTES} bytes",
            actual=f"{size} bytes",
        )
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise RecipeError(f"cannot read recipe file: {exc.strerror}", subject=f"file {path}") from None
    return decoded_text(data, f"file {path}")


_XML_ENCODING = re.compile(rb"""^<\?xml[^>]*?\sencoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def decoded_text(data: bytes, subject: str) -> str:
    """A recipe file's text as editors save it: UTF-8 with or without a byte-order mark (Notepad,
    PowerShell, Excel), UTF-16 with one, or the encoding an XML declaration names."""
    if data.startswith(codecs.BOM_UTF8):
        encoding, data = "utf-8", data[len(codecs.BOM_UTF8) :]
    elif data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        encoding = "utf-16"
    else:
        declared = _XML_ENCODING.match(data.lstrip())
        encoding = declared.group(1).decode("ascii") if declared else "utf-8"
    try:
        if codecs.lookup(encoding).name.startswith(("utf-16", "utf-32")) and not data.startswith(
            (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)
        ):  # the declaration was read as ASCII: the file is not UTF-16 (.NET's StringWriter says so)
            encoding = "utf-8"
    except LookupError:
        raise RecipeError(
            f"its XML declaration names an unknown encoding {encoding!r}", subject=subject
        ) from None
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        raise RecipeError(
            f"not {encoding} text at byte {exc.start}: save it as UTF-8", subject=subject
        ) from None


def load_recipes(path: str | Path, fmt: str | None = None) -> list[Recipe]:
    """Every recipe of a file (XML files may hold several)."""
    p = Path(path)
    text = read_text_bounded(p)
    kind = fmt or detect_format(p, text)
    loaders = {
        "xml": from_xml,
        "yaml": _from_yaml,
        "json": _from_json,
        "csv": _from_csv,
        "lines": _from_lines,
    }
    if kind not in loaders:
        raise RecipeError(f"unknown recipe format {kind!r}", expected=", ".join(FORMATS))
    recipes = loaders[kind](text, str(p))
    return [r.with_(source=str(p)) for r in recipes]


def _from_csv(text: str, where: str) -> list[Recipe]:
    """Commas, or semicolons as spreadsheets write CSV in many locales; names in quotes or not."""
    lines = [line.replace(";", ",").rstrip(",") for line in _uncommented(text) if line]
    recipe = Recipe.parse(",".join(lines))
    return [recipe.with_(names=tuple(n.strip().strip('"').strip("'").strip() for n in recipe.names))]


def _from_lines(text: str, where: str) -> list[Recipe]:
    return [Recipe(tuple(n for n in _uncommented(text) if n))]


def _recipe_from_mapping(item: Any, where: str, index: int) -> Recipe:
    if isinstance(item, list):  # its names, read as those under `fields`
        item = {"fields": item}
    if not isinstance(item, dict):
        raise RecipeError(f"recipe {index} must be a mapping or a list of names", subject=at(where))
    known = {"key", "direction", "frequency", "controller", "fields", "names"}
    unknown = sorted(set(item) - known)
    if unknown:
        raise RecipeError(
            f"recipe {index}: unknown key(s) {unknown}",
            subject=at(where),
            expected=", ".join(sorted(known)),
        )
    raw = item.get("fields", item.get("names"))
    if not isinstance(raw, list):
        raise RecipeError(f"recipe {index} needs a list under 'fields'", subject=at(where))
    names: list[str] = []
    declared: dict[str, str] = {}
    for entry in raw:
        name = entry.get("name") if isinstance(entry, dict) else entry
        if not isinstance(name, str):  # null, 5, `{timestamp: DOUBLE}` were the names "None", "5"
            raise RecipeError(f"recipe {index}: {entry!r:.40} is no name or {{name,type}}", subject=at(where))
        names.append(name.strip())
        if isinstance(entry, dict) and entry.get("type"):
            declared[names[-1]] = str(entry["type"])
    direction = item.get("direction")
    if direction not in (None, "input", "output"):
        raise RecipeError(
            f"recipe {index}: direction must be input or output", subject=at(where), actual=direction
        )
    frequency = item.get("frequency")
    try:  # a bool is no rate (`frequency: true` was 1 Hz)
        hz = None if frequency is None else float(frequency if not isinstance(frequency, bool) else "-")
    except (TypeError, ValueError, OverflowError):
        raise RecipeError(
            f"recipe {index}: frequency must be a number", subject=at(where), actual=repr(frequency)[:80]
        ) from None
    controller = item.get("controller")
    if isinstance(controller, float):  # YAML and JSON read 5.10 as the number 5.1
        raise RecipeError(
            f"recipe {index}: controller must be a version in quotes ('5.10', not 5.10: "
            f"read as the number {controller!r})",
            subject=at(where),
            actual=repr(controller),
        )
    key = item.get("key")
    if isinstance(key, (list, dict)):
        raise RecipeError(
            f"recipe {index}: key must be a name or number", subject=at(where), actual=repr(key)
        )
    return Recipe(
        tuple(names),
        direction=direction,
        frequency=hz,
        controller=str(controller) if controller is not None else None,
        key=str(key) if key is not None else None,  # `key: 1` is chosen by --recipe-key 1
        declared_types=declared,
    )


def _from_data(data: Any, where: str) -> list[Recipe]:
    if isinstance(data, dict) and "recipes" in data:
        items = data["recipes"]
    elif isinstance(data, list) and data and all(isinstance(x, str) for x in data):
        items = [data]
    elif isinstance(data, dict):
        items = [data]
    else:
        items = data
    if not isinstance(items, list) or not items:
        raise RecipeError("no recipes found", subject=at(where))
    return [_recipe_from_mapping(item, where, i) for i, item in enumerate(items, 1)]  # as pick_recipe


def _from_yaml(text: str, where: str) -> list[Recipe]:
    try:
        data = safe_yaml.load(text)
    except yaml.YAMLError as exc:
        raise RecipeError(f"not valid YAML: {exc}", subject=at(where)) from None
    return _from_data(data, where)


def _from_json(text: str, where: str) -> list[Recipe]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise RecipeError(f"not valid JSON at line {exc.lineno}: {exc.msg}", subject=at(where)) from None
    except RecursionError:
        raise RecipeError("JSON nests too deeply to be a recipe", subject=at(where)) from None
    except ValueError as exc:  # e.g. an integer of more digits than Python converts
        raise RecipeError(f"not valid JSON: {exc}", subject=at(where)) from None
    return _from_data(data, where)


# --- writing -----------------------------------------------------------------


def _as_mapping(recipe: Recipe) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key in ("key", "direction", "frequency", "controller"):
        value = getattr(recipe, key)
        if value is not None:
            out[key] = value
    out["fields"] = [
        {"name": n, "type": recipe.declared_types[n]} if n in recipe.declared_types else n
        for n in recipe.names
    ]
    return out


def dumps_recipes(recipes: list[Recipe], fmt: str, types: dict[str, str] | None = None) -> str:
    """Recipes as text of a format; `types` fills XML type attributes (name -> type)."""
    check_savable(recipes)
    if fmt == "csv":
        _single(recipes, fmt)
        return recipes[0].wire_text + "\n"
    if fmt == "lines":
        _single(recipes, fmt)
        return "".join(f"{n}\n" for n in recipes[0].names)
    if fmt == "yaml":
        return yaml.safe_dump({"recipes": [_as_mapping(r) for r in recipes]}, sort_keys=False)
    if fmt == "json":
        return json.dumps({"recipes": [_as_mapping(r) for r in recipes]}, indent=2) + "\n"
    if fmt == "xml":
        root = Element("rtde_config")
        for i, recipe in enumerate(recipes):
            element = SubElement(root, "recipe", key=recipe.key or f"recipe{i + 1}")
            for name in recipe.names:
                attrs = {"name": name}
                kind = recipe.declared_types.get(name) or (types or {}).get(name)
                if kind:
                    attrs["type"] = kind
                SubElement(element, "field", attrs)
        _indent(root)
        return '<?xml version="1.0"?>\n' + tostring(root, encoding="unicode") + "\n"
    raise RecipeError(f"unknown recipe format {fmt!r}", expected=", ".join(FORMATS))


def save_recipes(
    recipes: list[Recipe],
    path: str | Path,
    fmt: str | None = None,
    types: dict[str, str] | None = None,
) -> None:
    """Write `recipes` to `path`, appearing only complete (an existing file stays as it was if
    anything fails); the format from `fmt` or the file's suffix."""
    from rtde_spec.output.partfile import write_with

    p = Path(path)
    kind = fmt or detect_format(p, "")
    data = dumps_recipes(recipes, kind, types).encode("utf-8")
    write_with(p, lambda out: out.write(data))


def _single(recipes: list[Recipe], fmt: str) -> None:
    if len(recipes) != 1:
        raise RecipeError(f"the {fmt} format holds one recipe", actual=f"{len(recipes)} recipes")


def _indent(element: Element, level: int = 0) -> None:
    pad = "\n" + "  " * (level + 1)
    if len(element):
        element.text = pad
        for child in element:
            _indent(child, level + 1)
            child.tail = pad
        element[-1].tail = "\n" + "  " * level


def infer_direction(recipe: Recipe, inputs: set[str], outputs: set[str]) -> Direction:
    """The recipe's own direction; else input when every name is an input (register
    read-backs are rarely subscribed alone) or input-only names outnumber output-only
    ones; else output."""
    if recipe.direction is not None:
        return recipe.direction
    names = [n for n in recipe.names if n]
    if names and all(n in inputs for n in names):
        return "input"
    only_in = sum(1 for n in names if n in inputs and n not in outputs)
    only_out = sum(1 for n in names if n in outputs and n not in inputs)
    return "input" if only_in > only_out else "output"


def pick_recipe(
    recipes: list[Recipe],
    key: str | None,
    direction: Direction,
    inputs: set[str],
    outputs: set[str],
    *,
    where: str,
    how: str = "--recipe-key KEY",
) -> Recipe:
    """The recipe of a file to use, as UR's record.py picks one (`conf.get_recipe('out')`): the
    one keyed `key` (or numbered, from 1); without a key the only recipe, else the only one of
    `direction` (a recipe's own direction, else `infer_direction`); else a UsageError listing them.

    So UR's record_configuration.xml style files (state, setp, watchdog) need no key to record
    `state`: setp and watchdog name only input registers.
    """

    def label(number: int, recipe: Recipe) -> str:
        kind = infer_direction(recipe, inputs, outputs)
        size = f"{len(recipe.names)} field{'' if len(recipe.names) == 1 else 's'}"
        return f"{recipe.key or f'#{number}'} ({kind}, {size})"

    listing = ", ".join(label(n, r) for n, r in enumerate(recipes, 1))
    if key is not None:
        chosen = [r for r in recipes if r.key == key]
        if not chosen and key.lstrip("#").isdigit() and 1 <= int(key.lstrip("#")) <= len(recipes):
            chosen = [recipes[int(key.lstrip("#")) - 1]]
        if not chosen:
            raise UsageError(
                f"no recipe keyed {key!r}; its recipes: {listing}; give one of those keys", subject=at(where)
            )
        return chosen[0]
    if len(recipes) == 1:
        return recipes[0]
    fitting = [r for r in recipes if infer_direction(r, inputs, outputs) == direction]
    if len(fitting) == 1:
        return fitting[0]
    which = f"{len(fitting)} {direction} recipes" if fitting else f"no {direction} recipe"
    raise UsageError(
        f"holds {len(recipes)} recipes and {which}: {listing}; pick one with {how}", subject=at(where)
    )
