"""Emit _generated/dashboard.py and docs/reference/dashboard.md from spec/dashboard/commands.yaml.

The dashboard server speaks text, not the binary layouts of the protocol spec, so it
has its own meta-model (rtde_spec.metamodel.dashboard) and its own emitter.
"""

from __future__ import annotations

from rtde_spec.metamodel.dashboard import DashboardFile

from .render import GEN, MD_HEADER, literal_module, md_table


def emit_dashboard(table: DashboardFile) -> dict[str, str]:
    """Relative output path -> text, for the dashboard table of the loaded spec."""
    return {f"{GEN}/dashboard.py": _python(table), "docs/reference/dashboard.md": _markdown(table)}


def _python(table: DashboardFile) -> str:
    return literal_module(
        "Dashboard server commands and replies of spec/dashboard/commands.yaml.",
        "DASHBOARD",
        table.model_dump(mode="json"),
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
