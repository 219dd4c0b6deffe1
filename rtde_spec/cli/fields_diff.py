"""rtde-spec fields --diff A B: what one controller version has that another has not."""

from __future__ import annotations

from typing import Any

from rtde_spec.metamodel.catalogue import Catalogue
from rtde_spec.metamodel.versions import Version
from rtde_spec.output.text import print_json, table


def version_diff(catalogue: Catalogue, old: str, new: str) -> dict[str, Any]:
    """Fields added and removed from `old` to `new`, per interface, with each version's line."""
    from rtde_spec.metamodel.primary_fields import available, primary_fields

    lines = {v: catalogue.line_of(v) for v in (old, new)}
    out: dict[str, Any] = {
        "from": {"version": str(Version.parse(old)), "line": lines[old].id},
        "to": {"version": str(Version.parse(new)), "line": lines[new].id},
        "same_line": lines[old].id == lines[new].id,
    }
    for direction in ("input", "output"):
        infos = catalogue.fields(direction)
        before = {i.name for i in infos if catalogue.available(i, old)}
        after = {i.name for i in infos if catalogue.available(i, new)}
        out[f"rtde_{direction}s"] = {
            "added": [_rtde(i, catalogue) for i in infos if i.name in after - before],
            "removed": [_rtde(i, catalogue) for i in infos if i.name in before - after],
        }
    prim = primary_fields(catalogue)
    out["primary"] = {
        "added": [
            _prim(i) for i in prim if available(i, catalogue, new) and not available(i, catalogue, old)
        ],
        "removed": [
            _prim(i) for i in prim if available(i, catalogue, old) and not available(i, catalogue, new)
        ],
    }
    return out


def _rtde(info: Any, catalogue: Catalogue) -> dict[str, Any]:
    return {"name": info.name, "type": info.type, "since": {k: str(v) for k, v in info.since.items()}}


def _prim(info: Any) -> dict[str, Any]:
    return {
        "name": f"{info.message}.{info.name}",
        "type": info.type,
        "since": {k: str(v) for k, v in info.since.items()},
    }


def print_diff(catalogue: Catalogue, old: str, new: str, as_json: bool) -> int:
    result = version_diff(catalogue, old, new)
    if as_json:
        print_json(result)
        return 0
    a, b = result["from"], result["to"]
    names = {k: catalogue.lines[v["line"]].name for k, v in (("a", a), ("b", b))}
    print(f"{a['version']} ({names['a']}) -> {b['version']} ({names['b']})")
    if not result["same_line"]:
        print("different product lines: each line's fields are listed at that line's versions")
    rows = []
    for interface in ("rtde_inputs", "rtde_outputs", "primary"):
        for change in ("added", "removed"):
            for item in result[interface][change]:
                since = ", ".join(f"{k} {v}" for k, v in item["since"].items())
                rows.append([interface.replace("_", " "), change, item["name"], item["type"], since])
    if rows:
        print(table(["interface", "change", "field", "type", "since"], rows))
    print(f"\n{len(rows)} changes")
    return 0
