"""Apply an import to spec/ YAML in place, keeping comments, order and formatting.

ruamel.yaml's round-trip mode edits the parsed document and writes it back; only
the entries an import changes are touched. Each changed entry gets the document
in `sources`. The edited text is first put into a copy of the spec tree, which must
load, lint and generate (in memory); only then is the file replaced, atomically, with
its mode kept. Removals are applied only when asked for.
"""

from __future__ import annotations

import codecs
import os
import re
import shutil
import stat
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rtde_spec.errors import OutputError, RtdeSpecError, UsageError
from rtde_spec.importers import availability as av
from rtde_spec.importers.changes import Change
from rtde_spec.importers.model import DocField, DocLayoutField, Document
from rtde_spec.importers.yaml_text import dump, flow, round_trip
from rtde_spec.metamodel.schema import Spec

#: more removals than this from one document is a document that does not cover the spec
HANDFUL = 5


def replace_text(path: Path, text: str) -> None:
    """Write beside `path` and rename into place, keeping its mode; a read-only file is refused.

    The project's one way of writing a file (`partfile`): a failure leaves the old file as it was
    and no temporary file, names `path`, and a symlink is written through. Synced before the
    rename and the folder after: a power loss then leaves the old spec file or the new one, never
    an empty one."""
    from rtde_spec.output.partfile import write_with

    if path.exists() and (not os.access(path, os.W_OK) or not path.stat().st_mode & stat.S_IWUSR):
        raise UsageError(f"{path} is read-only; nothing written")
    data = text.encode("utf-8")
    write_with(path, lambda out: out.write(data), keep_mode=True, durable=True)


def check_tree(spec_dir: Path, rel: str, text: str) -> None:
    """Load, lint and generate a copy of the spec tree with `rel` replaced by `text`; raise if any fails."""
    from rtde_spec.metamodel.bundle import load_bundle

    with tempfile.TemporaryDirectory(prefix="rtde-spec-import-") as tmp:
        copy = Path(tmp) / "spec"
        try:
            shutil.copytree(spec_dir, copy, ignore=shutil.ignore_patterns(".*"))
            (copy / rel).write_bytes(text.encode("utf-8"))  # as replace_text writes it (no CRLF added)
        except (OSError, shutil.Error) as exc:  # a full TMPDIR: shutil.Error holds a list per file
            first = exc.args[0][0] if isinstance(exc, shutil.Error) and exc.args and exc.args[0] else None
            text = str(first[2] if isinstance(first, tuple) and len(first) == 3 else exc)
            why = "the disk is full" if "No space left" in text else text.split(":")[0]
            raise OutputError(
                f"{why}: the spec could not be copied there to be checked, so nothing was written "
                "(TMPDIR picks another folder)",
                subject=f"temporary folder {tmp}",
            ) from None
        try:
            bundle = load_bundle(copy)
            try:
                from codegen.generate import generate
            except ImportError:  # an installed package without the generator: loading and lint only
                return
            generate(bundle)
        except RtdeSpecError as exc:
            raise UsageError(
                f"the import would leave a spec that does not load; nothing written:\n{exc}"
            ) from None
        except Exception as exc:
            raise UsageError(
                f"the import would leave a spec codegen cannot generate; nothing written: "
                f"{type(exc).__name__}: {exc}"
            ) from None


@dataclass
class WriteResult:
    """What --write did: the changes written, and the removals held back (and why)."""

    written: list[Change] = field(default_factory=list)
    held: list[tuple[Change, str]] = field(default_factory=list)


def refuse_unreadable(changes: list[Change], doc: Document) -> None:
    """Nothing read through a wrong charset (U+FFFD, the replacement character) goes into the
    spec: a name or doc with it is a decoding accident, not UR's text."""
    for change in changes:
        if change.known is not None:
            continue
        row = change.extra.get("row")
        values = [change.field, change.new, getattr(row, "doc", ""), getattr(row, "name", "")]
        if any("\ufffd" in str(v) for v in values if v is not None):
            raise UsageError(
                f"{doc.path} line {change.line}: {change.field} ({change.where}) holds U+FFFD, a byte "
                "the document's charset could not decode; nothing written. Save the document as "
                "UTF-8 (or declare its charset) and import it again"
            )


def _add_source(entry: Any, source: str) -> None:
    sources = entry.get("sources")
    if sources is None:
        entry["sources"] = flow([source])
    elif source not in sources:
        sources.append(source)


def new_entry(row: DocField, doc: Document, spec: Spec) -> dict[str, Any]:
    """A fields.yaml entry for a field the document adds."""
    from rtde_spec.importers.diff import doc_availability

    entry: dict[str, Any] = {"name": row.name, "type": row.type}
    if row.doc:
        entry["doc"] = row.doc
    lines = spec.product_lines.product_lines
    if row.index is not None:
        entry["index"] = flow(list(row.index))
        per = {
            i: (av.apply({}, doc_availability(row, i, doc.line, spec), lines), None)
            for i in range(row.index[0], row.index[1] + 1)
        }
        parts = av.runs(per)
        if len(parts) == 1:
            if parts[0][2] is not None:
                entry["since"] = flow(dict(parts[0][2]))
        else:
            entry["ranges"] = [
                flow({"index": flow([a, b]), "since": flow(dict(s or {}))}) for a, b, s, _ in parts
            ]
    else:
        since = av.apply({}, doc_availability(row, None, doc.line, spec), lines)
        if since is not None:
            entry["since"] = flow(dict(since))
    entry["sources"] = flow([doc.source])
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
    entry["index"] = flow([parts[0][0], parts[-1][1]])
    if len(parts) == 1:
        entry.pop("ranges", None)
        if parts[0][2] is None:
            entry.pop("since", None)
        else:
            _insert(entry, "since", flow(dict(parts[0][2])))
        return
    entry.pop("since", None)
    ranges = []
    for low, high, since, reserved in parts:
        rng: dict[str, Any] = {"index": flow([low, high])}
        if since is not None:
            rng["since"] = flow(dict(since))
        if reserved is not None and reserved != entry.get("reserved"):
            rng["reserved"] = reserved
        ranges.append(flow(rng))
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
            entry["since"] = flow(dict(since or {}))
        return
    if change.what == "type":
        entry["type"] = change.new
    elif change.what == "description":
        entry["doc"] = change.new
    elif change.what == "range":
        from rtde_spec.importers.diff import doc_availability

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
                _insert(entry, "since", flow(dict(since)))
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
        member["since"] = flow(dict(since or {}))
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
            new["since"] = flow(dict(since))
        member["fields"].append(flow(new))
        return True
    node: Any = {"fields": member["fields"]}
    for part in change.field.split("."):
        node = next(f for f in node["fields"] if f["name"] == part)
    if change.what == "availability":
        since = av.apply(node.get("since") or member.get("since"), change.new, lines)
        if since is not None:
            node["since"] = flow(dict(since))
    elif change.what == "description":
        node["doc"] = change.new
    elif change.what == "type" and " in " not in str(change.new) and "[" not in str(change.new):
        node["type"] = change.new
    else:
        return False
    return True


def write_changes(
    changes: list[Change], doc: Document, spec: Spec, spec_dir: Path, allow_removals: bool = False
) -> WriteResult:
    """Apply the changes that are not known conflicts to a copy, check it, then replace the file.

    Removals need `allow_removals`; more than HANDFUL of them without it refuses the whole write.
    """
    refuse_unreadable(changes, doc)
    rel = "primary/interface.yaml" if doc.interface == "primary" else "rtde/fields.yaml"
    path = spec_dir / rel
    result = WriteResult()
    removals = [c for c in changes if c.known is None and c.kind == "removed"]
    if removals and not allow_removals:
        if len(removals) > HANDFUL:
            raise UsageError(
                f"the document would remove {len(removals)} fields (more than {HANDFUL}): it does not "
                "cover the spec (an abridged copy, a table that stops early, another edition); nothing "
                "written. Pass --allow-removals if it really drops them"
            )
        result.held += [(c, "a removal: pass --allow-removals to apply it") for c in removals]
    yaml = round_trip()
    raw = path.read_bytes()
    data = yaml.load(raw.decode("utf-8-sig").replace("\r\n", "\n"))
    for change in changes:
        if change.known is not None or (change.kind == "removed" and not allow_removals):
            continue
        decided = change.extra.get("decided")
        if decided is not None:  # a value the spec decided against, for a document of another id
            why = f"the spec records this value as a conflict of {', '.join(decided.sources)}"
            result.held.append((change, f"{why}; --source names the document if it is that one"))
            continue
        if doc.interface == "primary" and not _apply_primary(change, data, doc, spec):
            result.held.append((change, "a layout decision (a group, array, string): edit spec/primary"))
            continue
        if doc.interface != "primary":
            _apply_rtde(change, data, doc, spec)
        result.written.append(change)
    if result.written:
        text = dump(yaml, data)
        if b"\r\n" in raw:  # a Windows checkout's file: every line kept as it was, not rewritten to LF
            text = text.replace("\n", "\r\n")
        if raw.startswith(codecs.BOM_UTF8):
            text = "\ufeff" + text
        check_tree(spec_dir, rel, text)
        replace_text(path, text)
    return result


def write_overlay(changes: list[Change], doc: Document, spec: Spec, path: Path) -> int:
    """The fields the document adds, as a file for --extra-fields / RTDE_SPEC_EXTRA_FIELDS."""
    refuse_unreadable(changes, doc)
    yaml = round_trip()
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
    text = dump(yaml, out)
    _check_overlay(text, spec)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # a full disk, a file where a folder should be: named as a write error
        from rtde_spec.output.partfile import write_failed

        raise write_failed(exc, path) from None
    replace_text(path, text)
    return count


def _check_overlay(text: str, spec: Spec) -> None:
    """The overlay must load as --extra-fields loads it; checked before anything is written."""
    from rtde_spec.metamodel.loader import load_fields_file

    with tempfile.TemporaryDirectory(prefix="rtde-spec-overlay-") as tmp:
        probe = Path(tmp) / "overlay.yaml"
        probe.write_text(text, encoding="utf-8")
        try:
            load_fields_file(probe, spec, spec.fields)
        except RtdeSpecError as exc:
            raise UsageError(
                f"the overlay would not load with --extra-fields; nothing written:\n{exc}"
            ) from None
