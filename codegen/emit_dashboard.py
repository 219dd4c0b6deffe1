"""Emit _generated/dashboard.py and docs/reference/dashboard.md from spec/dashboard/commands.yaml.

The dashboard server speaks text, not the binary layouts of the protocol spec, so it
has its own meta-model (rtde_spec.spec.dashboard) and its own emitter.
"""

from __future__ import annotations

import pprint
from pathlib import Path

from rtde_spec.spec.dashboard import DashboardFile, load_dashboard

from .render import MD_HEADER, PY_HEADER, md_table

GEN = "rtde_spec/_generated"
SPEC_ROOT = Path(__file__).resolve().parent.parent / "spec"


def emit_dashboard(root: Path | str | None = None) -> dict[str, str]:
    """Relative output path -> text, for the dashboard table below spec root `root`."""
    table = load_dashboard(root if root is not None else SPEC_ROOT)
    return {f"{GEN}/dashboard.py": _python(table), "docs/reference/dashboard.md": _markdown(table)}


def _python(table: DashboardFile) -> str:
    literal = pprint.pformat(table.model_dump(mode="json"), width=100, sort_dicts=False)
    return (
        PY_HEADER
        + '"""Dashboard server commands and replies of spec/dashboard/commands.yaml."""\n\n'
        + "from typing import Any\n\n"
        + f"DASHBOARD: dict[str, Any] = {literal}\n"
    )


def _markdown(table: DashboardFile) -> str:
    out = [
        MD_HEADER,
        "# Dashboard server\n\n",
        f"Text commands on TCP port {table.port}, one per line ending in `\\n`, each answered by one\n",
        f"line. A client is greeted with `{table.greeting}`; a command the version does not have\n",
        f"gets `{table.unknown}`. Product lines: {', '.join(table.product_lines)}. ",
        f"Source: {table.doc_ref}.\n\n",
        *(f"Replaced on {line}: {text}\n\n" for line, text in table.replaced_by.items()),
    ]
    rows = []
    for c in table.commands:
        command = f"`{c.command}" + (f" <{c.argument}>`" if c.argument else "`")
        replies = "<br>".join(f"{k}: `{v}`" for k, v in c.replies.items())
        since = ", ".join(f"{line} {v}" for line, v in c.since.items())
        rows.append((command, replies, since, c.doc or ""))
    out.append(md_table(["command", "replies", "since", "what it does"], rows))
    out.append("\n## Values in replies\n\n")
    out.append(md_table(["value", "meaning"], [(f"`{{{k}}}`", v.doc) for k, v in table.values.items()]))
    return "".join(out)
