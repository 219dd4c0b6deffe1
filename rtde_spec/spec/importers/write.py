"""Apply an import to spec/ YAML in place, keeping comments, order and formatting.

ruamel.yaml's round-trip mode edits the parsed document and writes it back; only
the entries an import changes are touched. Each changed entry gets the document
in `sources`. Files are written beside the target and renamed into place.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path
from typing import Any

from rtde_spec.spec.importers import availability as av
from rtde_spec.spec.importers.changes import Change
from rtde_spec.spec.importers.model import DocField, DocLayoutField, Document
from rtde_spec.spec.schema import Spec


def _yaml() -> Any:
    from ruamel.yaml import YAML

    yaml = YAML(typ="rt")
    yaml.preserve_quotes = True
    yaml.width = 4096
    yaml.indent(mapping=2, sequence=4, offset=2)
    return yaml


def _flow(data: dict[str, Any] | list[Any]) -> Any:
    from ruamel.yaml.comments import CommentedMap, CommentedSeq

    node: Any = CommentedMap(data) if isinstance(data, dict) else CommentedSeq(data)
    node.fa.set_flow_style()
    return node


def _replace(path: Path, yaml: Any, data: Any) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            yaml.dump(data, out)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _add_source(entry: Any, source: str) -> None:
    sources = entry.get("sources")
    if sources is None:
        entry["sources"] = _flow([source])
    elif source not in sources:
        sources.append(source)


def new_entry(row: DocField, doc: Document, spec: Spec) -> dict[str, Any]:
    """A fields.yaml entry for a field the document adds."""
    from rtde_spec.spec.importers.diff import doc_availability

    entry: dict[str, Any] = {"name": row.name, "type": row.type}
    if row.doc:
        entry["doc"] = row.doc
    lines = spec.product_lines.product_lines
    if row.index is not None:
        entry["index"] = _flow(list(row.index))
        per = {
            i: (av.apply({}, doc_availability(row, i, doc.line, spec), lines), None)
            for i in range(row.index[0], row.index[1] + 1)
        }
        parts = av.runs(per)
        if len(parts) == 1:
            if parts[0][2] is not None:
                entry["since"] = _flow(dict(parts[0][2]))
        else:
            entry["ranges"] = [
                _flow({"index": _flow([a, b]), "since": _flow(dict(s or {}))}) for a, b, s, _ in parts
            ]
    else:
        since = av.apply({}, doc_availability(row, None, doc.line, spec), lines)
        if since is not None:
            entry["since"] = _flow(dict(since))
    entry["sources"] = _flow([doc.source])
    return entry


def _insert(entry: Any, key: str, value: Any) -> None:
    """Set a key; a new one goes before sources and conflicts, where the spec keeps such keys."""
    if key in entry:
        entry[key] = value
        return
    tail = [k for k in ("sources", "conflicts") if k in entry]
    entry.insert(list(entry).index(tail[0]) if tail else len(entry), key, value)


def _set_family(entry: Any, per: dict[int, tuple[av.Since, str | None]]) -> None:
    parts = av.runs(per)
    entry["index"] = _flow([parts[0][0], parts[-1][1]])
    if len(parts) == 1:
        entry.pop("ranges", None)
        if parts[0][2] is None:
            entry.pop("since", None)
        else:
            _insert(entry, "since", _flow(dict(parts[0][2])))
        return
    entry.pop("since", None)
    ranges = []
    for low, high, since, reserved in parts:
        rng: dict[str, Any] = {"index": _flow([low, high])}
        if since is not None:
            rng["since"] = _flow(dict(since))
        if reserved is not None and reserved != entry.get("reserved"):
            rng["reserved"] = reserved
        ranges.append(_flow(rng))
    _insert(entry, "ranges", ranges)


def _apply_rtde(change: Change, data: Any, doc: Document, spec: Spec) -> None:
    lines = spec.product_lines.product_lines
    key = "inputs" if change.where == "input" else "outputs"
    if change.what == "added":
        data.setdefault(key, []).append(new_entry(change.extra["row"], doc, spec))
        return
    if change.what == "direction":
        other = "outputs" if key == "inputs" else "inputs"
        entry = next(e for e in data[other] if e["name"] == change.field)
        data[other].remove(entry)
        data.setdefault(key, []).append(entry)
        _add_source(entry, doc.source)
        return
    entry = next(e for e in data[key] if e["name"] == change.field)
    if change.what == "removed":
        gone: dict[str, str | None] = {doc.line: None}
        gone.update({p.id: None for p in lines if p.inherits == doc.line})
        if entry.get("index") is not None:
            per = {i: (av.apply(s, gone, lines), r) for i, (s, r) in av.expand(entry).items()}
            if all(s == {} for s, _ in per.values()):
                data[key].remove(entry)
            else:
                _set_family(entry, per)
            return
        since = av.apply(entry.get("since"), gone, lines)
        if since == {}:
            data[key].remove(entry)
        else:
            entry["since"] = _flow(dict(since or {}))
        return
    if change.what == "type":
        entry["type"] = change.new
    elif change.what == "description":
        entry["doc"] = change.new
    elif change.what == "range":
        from rtde_spec.spec.importers.diff import doc_availability

        per = av.expand(entry)
        low, high = change.new
        row: DocField = change.extra["row"]
        for i in range(low, high + 1):
            if i not in per:  # a new index: the document's versions for it, the edge's reserved note
                edge = per[min(per)] if i < min(per) else per[max(per)]
                per[i] = (av.apply({}, doc_availability(row, i, doc.line, spec), lines), edge[1])
        _set_family(entry, {i: v for i, v in per.items() if low <= i <= high})
    elif change.what == "availability":
        if entry.get("index") is not None:
            per = av.expand(entry)
            span = change.index or (min(per), max(per))
            for i in range(span[0], span[1] + 1):
                if i in per:
                    per[i] = (av.apply(per[i][0], change.new, lines), per[i][1])
            _set_family(entry, per)
        else:
            since = av.apply(entry.get("since"), change.new, lines)
            if since is None:
                entry.pop("since", None)
            else:
                _insert(entry, "since", _flow(dict(since)))
    _add_source(entry, doc.source)


def snake(name: str) -> str:
    """camelCase as the spec spells primary fields: isRealRobotConnected -> is_real_robot_connected."""
    text = re.sub(r"(?<=[a-z0-9])([A-Z])", r"_\1", name)
    return text.lower()


def _apply_primary(change: Change, data: Any, doc: Document, spec: Spec) -> bool:
    """Added fields, types, versions and descriptions of existing members; False if not written."""
    family_name, _, member_name = change.where.partition("/")
    fam = next((f for f in data["families"] if f["name"] == family_name), None)
    member = next((m for m in (fam or {}).get("members", []) if m["name"] == member_name), None)
    if member is None or change.what == "removed":
        return False
    lines = spec.product_lines.product_lines
    if change.what == "availability" and change.field == member_name:
        since = av.apply(member.get("since"), change.new, lines)
        member["since"] = _flow(dict(since or {}))
        return True
    if change.what == "added":
        row: DocLayoutField = change.extra["row"]
        if row.group or not row.type or "[" in row.type or row.type.startswith(("string", "switch", "bytes")):
            return False  # groups, arrays and strings need a layout decision: left to a person
        new: dict[str, Any] = {
            "name": snake(row.name),
            "type": row.type,
            "doc": f"{row.name}: {row.doc}".rstrip(": "),
        }
        since = (
            av.apply({}, dict(change.extra.get("since", {})) or row.versions, lines) if row.versions else None
        )
        if since:
            new["since"] = _flow(dict(since))
        member["fields"].append(_flow(new))
        return True
    node: Any = {"fields": member["fields"]}
    for part in change.field.split("."):
        node = next(f for f in node["fields"] if f["name"] == part)
    if change.what == "availability":
        since = av.apply(node.get("since") or member.get("since"), change.new, lines)
        if since is not None:
            node["since"] = _flow(dict(since))
    elif change.what == "description":
        node["doc"] = change.new
    elif change.what == "type" and " in " not in str(change.new) and "[" not in str(change.new):
        node["type"] = change.new
    else:
        return False
    return True


def write_changes(changes: list[Change], doc: Document, spec: Spec, spec_dir: Path) -> list[Change]:
    """Apply the changes that are not known conflicts; return those written."""
    rel = "primary/interface.yaml" if doc.interface == "primary" else "rtde/fields.yaml"
    path = spec_dir / rel
    yaml = _yaml()
    data = yaml.load(path.read_text(encoding="utf-8"))
    written = []
    for change in changes:
        if change.known is not None:
            continue
        if doc.interface == "primary":
            if _apply_primary(change, data, doc, spec):
                written.append(change)
        else:
            _apply_rtde(change, data, doc, spec)
            written.append(change)
    if written:
        _replace(path, yaml, data)
    return written


def write_overlay(changes: list[Change], doc: Document, spec: Spec, path: Path) -> int:
    """The fields the document adds, as a file for --extra-fields / RTDE_SPEC_EXTRA_FIELDS."""
    yaml = _yaml()
    data: dict[str, Any] = {}
    count = 0
    for change in changes:
        if change.what == "added" and change.known is None and doc.interface == "rtde":
            key = "inputs" if change.where == "input" else "outputs"
            data.setdefault(key, []).append(new_entry(change.extra["row"], doc, spec))
            count += 1
    from ruamel.yaml.comments import CommentedMap

    out = CommentedMap(data)
    out.yaml_set_start_comment(f"Fields {doc.path} adds to the built-in spec (rtde-spec spec import -o)")
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists():
        path.touch()
    _replace(path, yaml, out)
    return count
