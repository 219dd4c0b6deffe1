"""rtde-spec spec import DOCUMENT: read a published UR document and diff it against spec/.

The importer and ruamel.yaml are imported only when this runs, so `rtde-spec --help`
stays fast.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rtde_spec.cli.conventions import describe
from rtde_spec.cli.report import EXIT_ERROR
from rtde_spec.errors import UsageError
from rtde_spec.metamodel.document_forms import FORMATS
from rtde_spec.output.text import print_json, table

if TYPE_CHECKING:
    from rtde_spec.importers.changes import Change


FORMS = FORMATS  # the document forms --form names


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("spec", help="work on spec/: import a published UR document")
    inner = p.add_subparsers(dest="spec_command", metavar="ACTION")
    inner.required = True
    imp = inner.add_parser(
        "import",
        help="read an RTDE guide, the primary or real-time interface document (text, Markdown, HTML, "
        ".xlsx); report changes",
        **describe(
            "Compares a published document (an RTDE guide, the primary/secondary or the real-time "
            "interface document, as rendered text, Markdown, HTML or UR's client-interface workbook) "
            "with the spec: added, removed, type, direction, availability per product line, register "
            "range and description changes, per field; real-time tables per edition (order, types, "
            "sizes, the message length). --write edits spec/ in place; -o writes the added fields as "
            "an --extra-fields overlay.",
            "rtde-spec spec import rtde-guide-5.30.txt",
            "rtde-spec spec import rtde-guide-5.30.txt -o new_fields.yaml",
            "rtde-spec spec import rtde-guide-5.30.txt --json --check",
        ),
    )
    imp.add_argument("document", type=Path, help="the document (its form is detected from the content)")
    imp.add_argument(
        "--spec-dir",
        type=Path,
        metavar="FOLDER",
        help="spec root (default: ./spec when there is one, else the installed package's spec; "
        "--write needs a spec folder)",
    )
    imp.add_argument("--json", action="store_true", help='print {"added", "removed", "changed"} as JSON')
    imp.add_argument(
        "--show-known", action="store_true", help="also list differences the spec records as conflicts"
    )
    imp.add_argument("--write", action="store_true", help="apply the differences to the spec YAML in place")
    imp.add_argument(
        "-o", "--output", type=Path, dest="overlay", metavar="FILE.yaml",
        help="write the added fields as an --extra-fields overlay file (default: none)",
    )  # fmt: skip
    imp.add_argument("--overlay", type=Path, dest="overlay", help=argparse.SUPPRESS)  # the old spelling
    imp.add_argument(
        "--source", metavar="ID", help="document id recorded in `sources` (default: from the document's form)"
    )
    imp.add_argument(
        "--line",
        choices=("cb3", "e-series", "polyscope-x"),
        help="product line the document is for (default: detected)",
    )
    imp.add_argument(
        "--form",
        choices=FORMS,
        help="the document's form (default: detected from its content)",
    )
    imp.add_argument(
        "--edition",
        metavar="VERSION",
        help="the controller version the document is written for (default: the newest its version "
        "cells name); fields newer than it are not reported removed",
    )
    imp.add_argument(
        "--allow-removals",
        action="store_true",
        help="let --write remove fields the document leaves out (never applied without it)",
    )
    imp.add_argument(
        "--check", action="store_true", help="exit 1 when there are differences the spec does not record"
    )
    imp.set_defaults(run=run)


def _cell(what: str, value: Any) -> str:
    from rtde_spec.importers.changes import value_text

    text = value_text(what, value)
    return "" if text is None else text if len(text) <= 70 else text[:67] + "..."


def _rows(changes: list[Change]) -> list[list[Any]]:
    rows = []
    for c in changes:
        index = f"[{c.index[0]}..{c.index[1]}]" if c.index else ""
        rows.append(
            [
                c.kind,
                c.field,
                c.where,
                c.what,
                index,
                _cell(c.what, c.old),
                _cell(c.what, c.new),
                c.line or "",
            ]
        )
    return rows


def _table_record(t: Any, spec: Any, doc: Any) -> dict[str, Any]:
    """Per table: rows read, fields, those the spec knows, and the spec's count for that edition."""
    from rtde_spec.importers.scope import expected_names

    entries = spec.fields.inputs if t.direction == "input" else spec.fields.outputs
    names = {e.name for e in entries}
    return {
        "heading": t.heading,
        "line": t.line,
        "direction": t.direction,
        "rows": t.rows,
        "fields": t.fields,
        "matched": len(set(t.names) & names),
        "spec": len(expected_names(spec, doc, t.direction)),
        "skipped": [{"line": n, "cell": c} for n, c in t.skipped],
    }


def _realtime_record(t: Any, doc: Any, args: argparse.Namespace) -> dict[str, Any]:
    """Per real-time table: rows read, its TOTAL, and what the spec sends at that edition."""
    spec_fields: int | None = None
    spec_bytes: int | None = None
    if t.edition and t.product_line:
        from rtde_spec.importers.realtime_diff import plan_for
        from rtde_spec.metamodel.catalogue import Catalogue
        from rtde_spec.metamodel.realtime import PRIMITIVES, load_realtime, realtime_spec

        spec = args.loaded_spec
        table = load_realtime(args.spec_dir) if args.spec_dir is not None else realtime_spec()
        fields = plan_for(table, Catalogue(spec), t.product_line, t.edition)
        spec_fields = len(fields)
        spec_bytes = 4 + sum(PRIMITIVES[f.type][1] * (f.count or 1) for f in fields)
    return {
        "title": t.title,
        "line": t.product_line,
        "edition": t.edition,
        "rows": len(t.rows),
        "total_bytes": t.total[1] if t.total else None,
        "spec_fields": spec_fields,
        "spec_bytes": spec_bytes,
        "skipped": [{"line": n, "cell": c} for n, c in t.skipped],
    }


def run(args: argparse.Namespace) -> int:
    from rtde_spec.importers import read_document

    spec = _spec_to_compare(args)
    args.loaded_spec = spec
    doc = read_document(
        args.document, spec, source=args.source, line=args.line, fmt=args.form, edition=args.edition
    )
    by_interface = _diff(args, doc, spec)
    changes = [c for found in by_interface.values() for c in found]
    new = [c for c in changes if c.known is None]
    known = [c for c in changes if c.known is not None]
    if args.json:
        _print_json(args, doc, spec, new, known)
    else:
        _print_report(args, doc, spec, new, known)
    for problem in doc.problems:
        print(f"warning: {args.document}: {problem}", file=sys.stderr)
    if args.write and doc.problems:
        # a copy that stops inside a table, or a table whose direction it does not say, is not the
        # whole document: what it lacks would be taken out of (or not checked against) the spec
        raise UsageError(
            f"{len(doc.problems)} problems reading the document (said above); nothing written: "
            "import a complete copy",
            subject=f"file {args.document}",
        )
    if args.write:
        changes = _write(args, doc, spec, by_interface)
        new = [c for c in changes if c.known is None]
    if args.overlay is not None:
        from rtde_spec.importers.write import write_overlay

        count = write_overlay(changes, doc, spec, args.overlay)
        print(f"wrote {count} added fields to {args.overlay}", file=sys.stderr)
    return EXIT_ERROR if args.check and (new or doc.problems) else 0


def _spec_to_compare(args: argparse.Namespace) -> Any:
    """The spec the document is compared with: the checkout's (--spec-dir, or ./spec), else the
    installed package's own; --write needs a checkout's."""
    from rtde_spec.cli.inputs import refuse_special
    from rtde_spec.metamodel.loader import load_spec

    wanted = (
        "give the published document (an RTDE guide or the primary interface document) as text, "
        "Markdown or HTML"
    )
    refuse_special(args.document, "a document", wanted)  # a pipe, a device, a folder: say which
    if not args.document.is_file():
        raise UsageError(f"no such file; {wanted}", subject=f"file {args.document}")
    if args.document.stat().st_size == 0:
        raise UsageError(f"the file is empty; {wanted}", subject=f"file {args.document}")
    _check_overlay_path(args.overlay)
    if args.spec_dir is None and Path("spec", "rtde").is_dir():
        args.spec_dir = Path("spec")
    if args.spec_dir is None and not args.write:  # an installed package: compare with its own spec
        from rtde_spec.metamodel.catalogue import Catalogue

        spec = Catalogue.builtin().spec
    elif args.spec_dir is None or not (args.spec_dir / "rtde").is_dir():
        where = args.spec_dir or Path("spec")
        raise UsageError(
            f"no spec here ({where.resolve()} holds no rtde/); --write edits a checkout's spec: run "
            "from the checkout's root or give --spec-dir path/to/spec (-o FILE writes an overlay instead)",
            subject=f"--spec-dir {where}",
        )
    else:
        spec = load_spec(args.spec_dir)
    _refuse_overlay_over_inputs(args)
    args.loaded_spec = spec
    return spec


def _refuse_overlay_over_inputs(args: argparse.Namespace) -> None:
    """-o never replaces a file the import reads: one of the spec's own files (`-o
    spec/rtde/fields.yaml` left the spec a 7-line overlay) or the document itself."""
    if args.overlay is None:
        return
    target = args.overlay.resolve()
    if target == args.document.resolve():
        raise UsageError("is the document being imported; give a new file name", subject=f"-o {args.overlay}")
    if args.spec_dir is not None and target.is_file() and target.is_relative_to(args.spec_dir.resolve()):
        raise UsageError(
            f"is a file of the spec {args.spec_dir}; the overlay is a file of its own (e.g. "
            "new_fields.yaml), and --write edits the spec",
            subject=f"-o {args.overlay}",
        )


def _check_overlay_path(overlay: Path | None) -> None:
    """-o names a file (not a folder): said before the document is read, not after the work."""
    if overlay is not None and overlay.is_dir():
        raise UsageError(
            "is a directory; give the overlay's file name (e.g. new_fields.yaml)", subject=f"-o {overlay}"
        )


def _diff(args: argparse.Namespace, doc: Any, spec: Any) -> dict[str, list[Change]]:
    """The document's changes per interface it holds tables of (rtde, primary, realtime)."""
    from rtde_spec.importers.diff import diff_fields
    from rtde_spec.importers.primary_diff import diff_primary

    by_interface: dict[str, list[Change]] = {}
    if doc.fields:
        by_interface["rtde"] = diff_fields(doc, spec)
    if doc.members:
        by_interface["primary"] = diff_primary(doc, spec)
    if doc.realtime:
        from rtde_spec.importers.realtime_diff import diff_realtime
        from rtde_spec.metamodel.catalogue import Catalogue
        from rtde_spec.metamodel.realtime import load_realtime, realtime_spec

        realtime = load_realtime(args.spec_dir) if args.spec_dir is not None else realtime_spec()
        by_interface["realtime"] = diff_realtime(doc, realtime, Catalogue(spec))
    return by_interface


def _print_json(
    args: argparse.Namespace, doc: Any, spec: Any, new: list[Change], known: list[Change]
) -> None:
    out: dict[str, Any] = {
        "document": str(args.document),
        "format": doc.format,
        "source": doc.source,
        "line": doc.line,
        "edition": doc.edition,
        "interfaces": doc.interfaces,
        "tables": [_table_record(t, spec, doc) for t in doc.tables],
        "realtime": [_realtime_record(t, doc, args) for t in doc.realtime],
        "unlisted": doc.unlisted,
        "remarks": doc.remarks,
        "problems": doc.problems,
        "added": [c.record() for c in new if c.kind == "added"],
        "removed": [c.record() for c in new if c.kind == "removed"],
        "changed": [c.record() for c in new if c.kind == "changed"],
    }
    if args.show_known:
        out["known"] = [c.record() for c in known]
    print_json(out)


def _print_report(
    args: argparse.Namespace, doc: Any, spec: Any, new: list[Change], known: list[Change]
) -> None:
    """What was read, table by table, then the changes and the counts."""
    head = ["change", "field", "where", "what", "index", "spec", "document", "line"]
    edition = f" {doc.edition}" if doc.edition else ""
    print(f"{args.document}: {doc.format}, {doc.source}, written for {doc.line}{edition}")
    if doc.members:
        fields = sum(len(m.fields) for m in doc.members)
        print(f"  {len(doc.members)} message tables read, {fields} field rows")
    for t in doc.tables:
        r = _table_record(t, spec, doc)
        print(
            f"  table {r['heading']!r} (line {r['line']}, {r['direction']}s): {r['rows']} rows read, "
            f"{r['fields']} fields, {r['matched']} matched the spec, the spec has {r['spec']}"
            + (f"; {len(t.skipped)} placeholder rows skipped" if t.skipped else "")
        )
        for line, cell in t.skipped:
            print(f"    skipped line {line}: {cell!r} (a placeholder, not a field)")
    for rt in doc.realtime:
        r = _realtime_record(rt, doc, args)
        total = f", TOTAL {r['total_bytes']} bytes" if r["total_bytes"] is not None else ""
        spec_part = (
            f"the spec sends {r['spec_fields']} fields, {r['spec_bytes']} bytes at {rt.edition}"
            if r["spec_fields"] is not None
            else "not compared"
        )
        scope = " ".join(filter(None, [rt.product_line, rt.edition])) or "no product line"
        print(
            f"  real-time table {rt.title!r} ({scope}): "
            f"{len(rt.rows)} rows read{total}; {spec_part}"
            + (f"; {len(rt.skipped)} placeholder rows skipped" if rt.skipped else "")
        )
    for direction, names in doc.unlisted.items():
        if direction.startswith("realtime"):
            continue  # said in the table's remark
        print(
            f"  {len(names)} spec {direction}s not listed: the {direction} table stops early "
            "(a placeholder row), so they are not reported as removed"
        )
    for remark in doc.remarks:
        print(f"  {remark}: not a change for {doc.line}")
    if new:
        print(table(head, _rows(new)))
    if args.show_known and known:
        print("\nknown conflicts (recorded in the spec):")
        rows = [[*r, c.known.decision if c.known else ""] for r, c in zip(_rows(known), known, strict=True)]
        print(table([*head, "decision"], rows))
    counts = {k: sum(c.kind == k for c in new) for k in ("added", "removed", "changed")}
    hint = "" if args.show_known or not known else " (--show-known lists them)"
    print(
        f"\n{counts['added']} added, {counts['removed']} removed, {counts['changed']} changed; "
        f"{len(known)} known conflicts{hint}"
    )
    decided = sorted({s for c in new if "decided" in c.extra for s in c.extra["decided"].sources})
    if decided:
        print(
            f"{sum('decided' in c.extra for c in new)} of them are conflicts the spec records for "
            f"{', '.join(decided)} (--write holds them): --source names the document if it is that one"
        )


def _write(
    args: argparse.Namespace, doc: Any, spec: Any, by_interface: dict[str, list[Change]]
) -> list[Change]:
    """--write: one interface's changes applied to the checkout's spec (real-time ones are held)."""
    from rtde_spec.importers.write import write_changes

    assert args.spec_dir is not None  # --write without a spec folder was refused above
    if "realtime" in by_interface:
        held = [c for c in by_interface.pop("realtime") if c.known is None]
        if held:
            print(
                f"not written: {len(held)} real-time changes; spec/realtime/interface.yaml is "
                "edited by hand (each field's since, and `lengths` with the document as source)",
                file=sys.stderr,
            )
    if len(by_interface) > 1:
        raise UsageError(
            f"the document holds tables of {' and '.join(by_interface)}; --write applies one "
            "interface at a time: import a copy holding only one"
        )
    changes = [c for found in by_interface.values() for c in found]
    new = [c for c in changes if c.known is None]
    result = write_changes(changes, doc, spec, args.spec_dir, allow_removals=args.allow_removals)
    for change, why in result.held:
        print(f"not written: {change.field} ({change.where}) {change.what}: {why}", file=sys.stderr)
    print(
        f"wrote {len(result.written)} of {len(new)} changes to {args.spec_dir}; run `python -m codegen`",
        file=sys.stderr,
    )
    return changes
