"""Names a narrow column wrapped over lines ("actual_joint_" / "voltage"): when the parts are one.

A PDF's name column is narrow, so long names break where a line may break: after a `_`
(what a typesetter or `<wbr>` allows), or, in a column with no such place, inside a word
("actual_tool_accelero" / "meter"). The rule, the same for every form that wraps:

- a part ending in `_`, or a part starting with one, is a piece of one name: no field name
  ends or starts with `_`, so the parts are rejoined without a space;
- a break inside a word leaves no mark: the parts are rejoined only when the whole is a name
  the spec knows and the first part alone is not (a new field wrapped there cannot be told
  from two cells, and is reported with its line, never guessed);
- a part ending in a line-break hyphen (`actual_joint_volt-` / `age`, a PDF viewer's copy) goes
  on without it, where the name has a `_` before the break or the whole is a known name;
- a part with spaces ("(X=[0..48])", a family's note) goes on the name with a space.
"""

from __future__ import annotations

import re
from collections.abc import Collection

from rtde_spec.metamodel.schema import Spec

#: a piece of a name: identifier characters only (`{X}` kept for families)
FRAGMENT = re.compile(r"[A-Za-z0-9_{}]+")
#: the same, maybe ended by a line-break hyphen
HYPHENATED = re.compile(r"[A-Za-z0-9_{}]+-?")


def known_names(spec: Spec) -> frozenset[str]:
    """The spec's field names as the guides write them (a family as `..._X`)."""
    entries = [*spec.fields.inputs, *spec.fields.outputs]
    return frozenset(e.name.replace("{X}", "X") for e in entries)


def joins(first: str, second: str, known: Collection[str], inside_word: bool = True) -> bool | None:
    """Whether `second` continues the name `first` wrapped: True, False (two cells), or None when
    only a break inside a word could make them one and the spec does not know the whole.
    `inside_word=False` (cells one per line, where a short comment may precede a name) refuses a
    break inside a word unless a part holds a `_`, as every field name but a few short ones does."""
    if first.endswith("-") and FRAGMENT.fullmatch(first[:-1]) and FRAGMENT.fullmatch(second):
        # a line-break hyphen ("actual_joint_volt-" / "age" in a PDF viewer's copy): no field name
        # holds a "-"; taken where the name has a `_`, or the whole is a name the spec knows
        whole = first[:-1] + second
        return "_" in whole and ("_" in first or whole in known)
    if not (FRAGMENT.fullmatch(first) and FRAGMENT.fullmatch(second)):
        return False
    if first.endswith("_") or second.startswith("_"):
        return True
    whole = first + second
    if whole in known and first not in known:
        return True
    if not inside_word and "_" not in first:
        return False
    return None


def join_parts(parts: list[str], known: Collection[str]) -> tuple[list[str], list[int]]:
    """The cells of the lines of one name cell: the parts rejoined by the rule; where a break
    inside a word cannot be told (None above), the part starts a cell of its own and its index
    in `parts` is returned, to be reported."""
    cells = [parts[0]]
    unsure: list[int] = []
    for k, part in enumerate(parts[1:], start=1):
        if not FRAGMENT.fullmatch(part):
            cells[-1] = f"{cells[-1]} {part}"  # a family's "(X=[0..48])"
            continue
        last = cells[-1].rsplit(" ", 1)[-1]
        verdict = joins(last, part, known) if last == cells[-1] else False
        if verdict:
            cells[-1] = cells[-1].removesuffix("-") + part
        else:
            if verdict is None:
                unsure.append(k)
            cells.append(part)
    return cells, unsure


def join_text(parts: list[str]) -> str:
    """The wrapped lines of a comment as one text: a line broken after `/` or `_` ("Fieldbus/" /
    "PLC", "speed_" / "slider_fraction") goes on without a space, as nothing was there."""
    out = ""
    for part in (p.strip() for p in parts):
        if part:
            out = part if not out else out + ("" if out.endswith(("/", "_")) else " ") + part
    return out
